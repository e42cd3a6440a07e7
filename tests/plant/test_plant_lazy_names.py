"""The plant package's lazily loaded names (PEP 562, seed 4201 [36]): ``dir(plant)`` lists what
the package has, loaded or not.

``__dir__`` must give the module's own names (its globals: ``__all__``, ``__getattr__``, each
name already loaded and each submodule imported) together with every name ``__getattr__`` will
load on demand, sorted and without repeats, and each listed export must resolve."""
import importlib

import plant


def test_dir_of_the_plant_package_lists_its_globals_and_every_name_it_loads_on_demand():
    """dir() is the sorted union of vars(package) and __all__ (no name twice), and holds the
    dunders a module always has; a name loaded since stays listed once."""
    listed = dir(plant)
    assert listed == sorted(set(vars(plant)) | set(plant.__all__))
    assert len(listed) == len(set(listed))
    for name in ("__all__", "__getattr__", "__dir__", "__name__", "__doc__", "importlib"):
        assert name in listed
    name = plant.__all__[0]
    getattr(plant, name)
    assert name in vars(plant) and dir(plant).count(name) == 1
    assert dir(plant) == sorted(set(vars(plant)) | set(plant.__all__))


def test_each_name_in_dir_of_the_plant_package_resolves():
    """Every listed name is an attribute of the package (loaded on demand if need be), and an
    export is the object its submodule defines (or that submodule)."""
    for name in dir(plant):
        value = getattr(plant, name)
        if name in plant.__all__:
            module = importlib.import_module(f"plant.{plant._EXPORTS[name]}")
            assert value is (module if plant._EXPORTS[name] == name else getattr(module, name))
