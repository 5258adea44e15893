"""AL: names, grammar (Lark), AST with source positions, interpreter."""
