"""Builds parcosim's C kernels (kernels/build.py) whenever the package is built or installed
(``pip install -e .`` included); the rest of the configuration is in pyproject.toml."""
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py


def _kernel_build():
    """kernels/build.py loaded by path (the build environment has no numpy for ``kernels``)."""
    import importlib.util

    path = Path(__file__).resolve().parent / "kernels" / "build.py"
    spec = importlib.util.spec_from_file_location("parcosim_kernel_build", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


class BuildWithKernels(build_py):
    def run(self):
        library = _kernel_build().build()      # in the source tree: editable installs load it there
        super().run()
        if not self.editable_mode:   # a wheel carries its own copy
            target = Path(self.build_lib) / "kernels" / library.name
            target.parent.mkdir(parents=True, exist_ok=True)
            self.copy_file(str(library), str(target))


setup(cmdclass={"build_py": BuildWithKernels})
