"""HTTP service for synth (FastAPI)."""
