"""A package's public names, loaded from their modules on first use (PEP 562).

A node imports one module of its package; a package ``__init__`` that imported every module eagerly would load
rclpy, rosbags or matplotlib into processes that never use them. ``lazy_exports`` gives the package its
``__all__`` and a module-level ``__getattr__`` that imports a name's module when the name is first asked for.
"""
from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from typing import Any


def lazy_exports(package: str, modules: Mapping[str, tuple[str, ...]]) -> tuple[list[str], Callable[[str], Any]]:
    """The ``__all__`` and the ``__getattr__`` of a package whose public names live in its modules.

    Parameters
    ----------
    package : str
        The package's name (its ``__name__``).
    modules : mapping of str to tuple of str
        Each module of the package (its name without the package) and the public names it defines.

    Returns
    -------
    list of str
        ``__all__``: every name, sorted.
    callable
        The package's ``__getattr__``: the name imported from its module; AttributeError for any other name.
    """
    home = {name: module for module, names in modules.items() for name in names}

    def __getattr__(name: str) -> Any:
        module = home.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        return getattr(importlib.import_module(f"{package}.{module}"), name)

    return sorted(home), __getattr__
