"""Plugin discovery: one module per entry in a package, found by an attribute it defines.

The one helper behind every "adding X is adding a file" folder (case kinds, CLI commands, solver checks,
diagnosis effects, bench areas), in the way meshio's ``register_format`` is shared by its format modules.
A plugin module is any non-private module of the package that defines all the ``required`` attributes.
"""
from __future__ import annotations

import importlib
import pkgutil
from types import ModuleType


def module_names(package: str) -> list[str]:
    """Names (sorted) of the non-private modules directly in ``package`` (dotted name), without importing them."""
    pkg = importlib.import_module(package)
    return sorted(i.name for i in pkgutil.iter_modules(pkg.__path__) if not i.name.startswith("_"))


def plugin(package: str, name: str, required: tuple[str, ...]) -> ModuleType | None:
    """The module ``package.name`` if it exists and defines every attribute in ``required``, else None."""
    if name not in module_names(package):
        return None
    mod = importlib.import_module(f"{package}.{name}")
    return mod if all(hasattr(mod, a) for a in required) else None


def plugins(package: str, required: tuple[str, ...], *, skip_broken: bool = False) -> list[ModuleType]:
    """Every plugin module of ``package`` (in module-name order) defining all ``required`` attributes.

    ``skip_broken``: a module that fails to import is left out (it is reported when asked for by name)
    instead of raising.
    """
    out = []
    for name in module_names(package):
        try:
            mod = importlib.import_module(f"{package}.{name}")
        except Exception:
            if skip_broken:
                continue
            raise
        if all(hasattr(mod, a) for a in required):
            out.append(mod)
    return out
