"""The version of fosmodel, set in one place: ``pyproject.toml``.

It is read from the installed distribution's metadata.  A module of its own so that the
modules that stamp it into files need not import the package's ``__init__`` (which imports
them).
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("fosmodel")
except PackageNotFoundError:  # a source tree on sys.path that was never installed
    __version__ = "0+unknown"
