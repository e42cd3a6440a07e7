"""The product packages' lazily loaded names (PEP 562, seed 4201 [36]): ``dir(package)`` lists
what the package has, loaded or not.

For each package that loads its exports on demand (a ``_EXPORTS`` table: plant and motor),
``__dir__`` must give the module's own names (its globals: ``__all__``, ``__getattr__``, each
name already loaded and each submodule imported) together with every name ``__getattr__`` will
load on demand, sorted and without repeats, and each listed export must resolve."""
import importlib

import pytest

from tests.repo.test_layout import PACKAGES

LAZY = [name for name in PACKAGES if hasattr(importlib.import_module(name), "_EXPORTS")]


def test_plant_and_motor_are_among_the_lazily_loaded_packages():
    """Catches the discovery below finding none (every test after it would pass vacuously)."""
    assert {"plant", "motor"} <= set(LAZY)


@pytest.mark.parametrize("name", LAZY)
def test_dir_of_the_package_lists_its_globals_and_every_name_it_loads_on_demand(name):
    """dir() is the sorted union of vars(package) and __all__ (no name twice), and holds the
    dunders a module always has; a name loaded since stays listed once."""
    package = importlib.import_module(name)
    listed = dir(package)
    assert listed == sorted(set(vars(package)) | set(package.__all__))
    assert len(listed) == len(set(listed))
    for dunder in ("__all__", "__getattr__", "__dir__", "__name__", "__doc__", "importlib"):
        assert dunder in listed
    export = package.__all__[0]
    getattr(package, export)
    assert export in vars(package) and dir(package).count(export) == 1
    assert dir(package) == sorted(set(vars(package)) | set(package.__all__))


@pytest.mark.parametrize("name", LAZY)
def test_each_name_in_dir_of_the_package_resolves(name):
    """Every listed name is an attribute of the package (loaded on demand if need be), and an
    export is the object its submodule defines (or that submodule)."""
    package = importlib.import_module(name)
    for listed in dir(package):
        value = getattr(package, listed)
        if listed in package.__all__:
            where = package._EXPORTS[listed]
            module = importlib.import_module(f"{name}.{where}")
            assert value is (module if where == listed else getattr(module, listed))
