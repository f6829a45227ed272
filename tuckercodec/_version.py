"""The library version (the file format carries its own version, see spec/FORMAT.md)."""

__version__ = "0.2.0"
