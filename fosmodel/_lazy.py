"""The public names of a package, each imported from its module the first time it is used.

A package's ``__init__`` declares its public names (``__all__``) and the module each comes
from, and gets its module-level ``__getattr__`` and ``__dir__`` (PEP 562) from
:func:`attach`, as scikit-image and SciPy do with ``lazy_loader.attach`` (Scientific Python
SPEC 1).  ``from fosmodel.io import load_record`` then imports the loader, and pandas with
it, but ``import fosmodel.io`` or the command line's start imports nothing heavy.  Type
checkers and editors read the same names from the package's ``if TYPE_CHECKING:`` imports;
``tests/test_public_api.py`` holds those imports, the table and ``__all__`` equal.

A public name must not be the name of a module of its package: importing that module sets
the package's attribute to the module, which would then hide the name.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Mapping, Sequence


def attach(package: str, homes: Mapping[str, Sequence[str]]
           ) -> tuple[Callable[[str], object], Callable[[], list[str]]]:
    """Return the ``__getattr__`` and ``__dir__`` of ``package``, which exports ``homes``.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    homes : mapping of str to sequence of str
        Each module of the package (relative: ``"loader"``, ``"core.fos"``) and the public
        names it holds.

    Returns
    -------
    __getattr__, __dir__
        ``__getattr__(name)`` imports ``name``'s module, keeps the value in the package (the
        next use finds it there) and returns it; ``__dir__()`` lists the package's
        ``__all__``.
    """
    where = {name: module for module, names in homes.items() for name in names}

    def __getattr__(name: str) -> object:
        if name not in where:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(f"{package}.{where[name]}"), name)
        setattr(sys.modules[package], name, value)
        return value

    def __dir__() -> list[str]:
        return sorted(sys.modules[package].__all__)

    return __getattr__, __dir__
