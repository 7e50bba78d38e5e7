"""The program's name and version, as written into every file's ``extraction.generator``."""

__all__ = ["GENERATOR", "PROG", "__version__"]

__version__ = "0.1.0"
PROG = "loudscape-extract"
GENERATOR = f"{PROG} {__version__}"
