"""cadsim: simulation -> rendering -> detection -> frame-pair datasets for correspondence identification."""

__version__ = "0.1.0"
