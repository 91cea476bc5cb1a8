"""Sensing: depth noise, the detection adapter, appearance features and box projection (pixels -> nodes)."""
