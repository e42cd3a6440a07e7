"""Old module names kept working after the layout of issue 29: ``import fmus.master``,
``python -m scenarios.tools``, ... load the module at its new place.

:func:`install` puts one finder first on ``sys.meta_path`` for a table old name -> new name.
An old name imports the new module itself (``sys.modules`` holds one object under both
names, so a monkeypatch through either is seen by both), and ``python -m OLD`` runs the new
module's code as ``__main__``.  The tables are in ``fmus/__init__.py`` and
``scenarios/__init__.py``; tests/repo/test_layout.py checks that every new name exists and that
no product module imports an old one.
"""
from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys


class MovedModules(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finder and loader of the old names of ``table`` (old dotted name -> new dotted name)."""

    def __init__(self, table: dict):
        self.table = dict(table)

    def find_spec(self, fullname, path=None, target=None):
        if fullname not in self.table:
            return None
        new = importlib.util.find_spec(self.table[fullname])
        if new is None:
            raise ImportError(f"{fullname} moved to {self.table[fullname]}, which does not exist", name=fullname)
        return importlib.util.spec_from_loader(fullname, self, origin=new.origin)

    def create_module(self, spec):
        module = importlib.import_module(self.table[spec.name])
        spec.loader_state = module.__spec__      # the import system sets the old name's spec on it
        return module

    def exec_module(self, module):
        module.__spec__ = module.__spec__.loader_state      # its own spec back

    def get_code(self, fullname):
        """The new module's code (``python -m OLD`` runs it)."""
        new = importlib.util.find_spec(self.table[fullname])
        return new.loader.get_code(new.name)


def install(table: dict) -> MovedModules:
    """Make the old names of ``table`` importable (first on ``sys.meta_path``: an old name can
    also be a folder of built FMUs, ``fmus/build``, which the path finder would take as a
    namespace package)."""
    finder = MovedModules(table)
    sys.meta_path.insert(0, finder)
    return finder
