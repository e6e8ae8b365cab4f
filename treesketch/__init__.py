"""TreeSketch front door: predict_then_refine(), the CLI and the HTTP service."""
