"""Build parcosim's C kernels (``kernels/src/*.c``) into one shared library.

``pip install -e .`` runs :func:`build` (``setup.py``); ``python -m kernels.build`` rebuilds
by hand, ``python -m kernels.build --sanitize --out DIR`` builds the AddressSanitizer and
UndefinedBehaviorSanitizer variant the tests run the kernels under.

The library carries the SHA-256 of its sources and flags (``pc_sources_hash``): the loader
(:mod:`kernels`) compares it with the sources beside it and rebuilds a stale library when a
compiler is there, so an edited kernel never runs as its old binary.
"""
from __future__ import annotations

import argparse
import hashlib
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
SOURCES = HERE / "src"
LIBRARY = HERE / "libparcosim_kernels.so"

#: C11, warnings as errors, no contraction of a*b+c into an FMA (results must not depend on
#: the CPU), no fast-math.  -O3 and -fno-math-errno (sqrt inline, no errno to set) change no
#: result: every operation and its order stay (docs/benchmarks.md, "Compiled mode at 1000x").
#: -fno-semantic-interposition: the library's own calls of its exported functions may be inlined
#: (no other library replaces them; the FMUs' builds hide them anyway), no result changes.
FLAGS = ("-std=c11", "-O3", "-fno-math-errno", "-fno-semantic-interposition", "-fPIC", "-shared", "-Wall",
         "-Wextra", "-Werror", "-Wshadow", "-ffp-contract=off", "-fno-fast-math")
SANITIZE = ("-fsanitize=address,undefined", "-fno-sanitize-recover=undefined", "-fno-omit-frame-pointer", "-g",
            "-O1")


class NoCompiler(RuntimeError):
    """No C compiler on this machine: parcosim's kernels cannot be built."""


def compiler() -> str:
    """``$CC``, else ``cc`` or ``gcc`` on the PATH; raises :class:`NoCompiler` naming what to install."""
    for name in (os.environ.get("CC"), "cc", "gcc", "clang"):
        if name and shutil.which(name):
            return shutil.which(name)
    raise NoCompiler("parcosim's C kernels need a C compiler and none was found (set CC, or install gcc: "
                     "'apt-get install gcc libc6-dev' on Debian/Ubuntu, Xcode's command line tools on macOS)")


def source_files() -> list:
    """The C sources and headers, sorted."""
    return sorted(p for p in SOURCES.iterdir() if p.suffix in (".c", ".h"))


def sources_hash(sanitize: bool = False) -> str:
    """SHA-256 (hex, 16 digits) of the sources, their names and the flags."""
    digest = hashlib.sha256(" ".join(FLAGS + (SANITIZE if sanitize else ())).encode())
    for path in source_files():
        digest.update(path.name.encode() + b"\0" + path.read_bytes())
    return digest.hexdigest()[:16]


def build(out: Path | None = None, sanitize: bool = False) -> Path:
    """Compile every ``src/*.c`` into one shared library at ``out`` (default
    :data:`LIBRARY`); written to a temporary file first and renamed, so a process loading it
    meanwhile sees the old or the new library whole.

    Raises
    ------
    NoCompiler
        No C compiler.
    subprocess.CalledProcessError
        The compiler refused the sources (its messages are on stderr).
    """
    out = Path(out) if out is not None else LIBRARY
    if out.is_dir():
        out = out / LIBRARY.name
    cc = compiler()
    flags = FLAGS + (SANITIZE if sanitize else ())
    sources = [str(p) for p in source_files() if p.suffix == ".c"]
    fd, tmp = tempfile.mkstemp(prefix=out.name + ".", suffix=".tmp", dir=out.parent)
    os.close(fd)
    try:
        subprocess.run([cc, *flags, f'-DPC_SOURCES_HASH="{sources_hash(sanitize)}"', f"-I{SOURCES}",
                        *sources, "-o", tmp, "-lm"], check=True)
        os.chmod(tmp, 0o755)
        os.replace(tmp, out)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m kernels.build", description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=None, help="library path or folder (default: beside the sources)")
    parser.add_argument("--sanitize", action="store_true", help="AddressSanitizer + UndefinedBehaviorSanitizer build")
    args = parser.parse_args(argv)
    try:
        print(build(args.out, args.sanitize))
    except NoCompiler as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    except subprocess.CalledProcessError:
        print("error: the C compiler refused parcosim's kernels (messages above)", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
