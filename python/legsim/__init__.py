"""legsim: the Python API of the legsim core (a ctypes binding of legsim.h)."""
__version__ = "0.1.0"
