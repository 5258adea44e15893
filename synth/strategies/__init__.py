"""strategies stage of synth (see docs/design.md)."""
