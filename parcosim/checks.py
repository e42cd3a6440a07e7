"""What ``parcosim`` refuses before it works, and how: one line, exit status 2, nothing left behind.

:class:`CommandError` is a refusal made before any work; the parser (:class:`Parser`) refuses
in one line instead of argparse's usage block; its types refuse a value naming the option;
:func:`check_output` refuses an output the command could not write; :func:`remove_if_empty`
takes back the folders a refused command made.
"""
from __future__ import annotations

import argparse
import difflib
import math
import os
from pathlib import Path


class CommandError(ValueError):
    """A command refused before it did anything: printed as one line, exit status 2, after
    ``head`` (the command that refused it, as argparse names it; default ``parcosim: error``)."""

    def __init__(self, message: str, head: str = "parcosim: error"):
        super().__init__(message)
        self.head = head


class Parser(argparse.ArgumentParser):
    """argparse's parser whose refusal is one line (no usage block): :class:`CommandError`."""

    def error(self, message):
        raise CommandError(f"{message} (`{self.prog} --help` lists the options)", head=self.prog)


def at_least(least: int, name: str):
    """An argparse type: an integer >= ``least``, refused naming the option and the value."""
    def check(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            value = None
        if value is None or value < least:
            raise argparse.ArgumentTypeError(f"{name} = {text} must be an integer >= {least}")
        return value
    return check


def non_negative(name: str):
    """An argparse type: a finite float >= 0."""
    def check(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        if not (math.isfinite(value) and value >= 0.0):
            raise argparse.ArgumentTypeError(f"{name} = {text} must be a finite number >= 0")
        return value
    return check


def suggestion(name: str, names) -> str:
    """'; did you mean X?' for the closest of ``names`` to a misspelled ``name`` (difflib), or ''."""
    close = difflib.get_close_matches(name, list(names), n=1, cutoff=0.6)
    return f"; did you mean {close[0]!r}?" if close else ""


def first_missing(path: Path) -> Path | None:
    """The outermost folder of ``path`` that does not exist yet (what the command will make), or None."""
    missing = None
    for folder in (path, *path.parents):
        if folder.exists() or folder.is_symlink():
            break
        missing = folder
    return missing


def check_output(path, is_file: bool) -> None:
    """Refuse, before any work, an output the command could not write: an existing folder where
    a file goes, a file where a folder goes, a folder we may not write in.  Makes nothing."""
    path = Path(path)
    if is_file and path.is_dir():
        raise CommandError(f"{path} is a folder; give the file to write")
    folder = path.parent if is_file else path
    existing = next((f for f in (folder, *folder.parents) if f.exists()), Path.cwd())
    if not existing.is_dir():
        raise CommandError(f"{path} is not writable: {existing} is a file, not a folder")
    if not os.access(existing, os.W_OK | os.X_OK):
        raise CommandError(f"{path} is not writable: no permission to write in folder {existing}")


def remove_if_empty(folder: Path | None) -> None:
    """Remove ``folder`` (made by a refused command) if it holds no file, its empty sub-folders too."""
    if folder is None or not folder.is_dir():
        return
    tree = list(os.walk(folder, topdown=False))
    if any(files for _, _, files in tree):
        return          # a file anywhere: nothing goes (not even the empty folders walked before it)
    for root, dirs, _ in tree:
        for d in dirs:
            try:
                os.rmdir(os.path.join(root, d))
            except OSError:
                return
    try:
        os.rmdir(folder)
    except OSError:
        pass
