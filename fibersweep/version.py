"""The installed package's version, a base value every layer may record."""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("fibersweep")
except PackageNotFoundError:  # running from a source tree without install
    __version__ = "0.0.0+unknown"

__all__ = ["__version__"]
