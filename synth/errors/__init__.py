"""errors stage of synth (see docs/design.md)."""
