"""hdsim: a harmonic drive (strain wave gear) simulator."""

__version__ = "0.1.0"
