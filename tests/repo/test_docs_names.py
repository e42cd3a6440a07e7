"""Every command, option, choice and repository path the README and docs/ name exists, and every
default docs/index.md states is the parser's (issue 29, item 4).

Catches: an option renamed or removed without the docs (``parcosim run --coupling`` still
documented after a rename), a file moved or deleted that a page still points at, a default
changed in the parser but not in the reference, a help text whose "(default: X)" lies.
"""
from __future__ import annotations

import argparse
import importlib.util
import itertools
import re

import pytest

from motor.cli import _parser as motor_parser
from parcosim.cli import _parser
from tests.support.paths import ROOT

PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
#: Paths that name what a command writes or what an FMU holds, not files of the repository.
OUTPUT_PREFIXES = ("out/", "fmus/build", "resources/", "binaries/", "documentation/", "sources/")


def _commands() -> dict:
    """Command name -> its parser (identify-motor: motor.cli's)."""
    parser = _parser()
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    commands = dict(action.choices)
    commands["identify-motor"] = motor_parser()
    return commands


COMMANDS = _commands()


def _options(command: str) -> dict:
    """Option string -> its action."""
    return {s: a for a in COMMANDS[command]._actions for s in a.option_strings}


def _code(text: str) -> list:
    """(page line, code) of every backtick span and every line of a code block."""
    found, fenced = [], False
    for number, line in enumerate(text.splitlines(), 1):
        if line.startswith("```"):
            fenced = not fenced
            continue
        if fenced or line.startswith("    "):
            found.append((number, line.strip()))
        else:
            found += [(number, span) for span in re.findall(r"`([^`]+)`", line.replace("\\|", "|"))]
    return found


def _mentions():
    """(where, command, the text after it) of every ``parcosim COMMAND ...`` in code."""
    for page in PAGES:
        for number, code in _code(page.read_text(encoding="utf-8")):
            for match in re.finditer(r"(?:^|[\s(|])parcosim ([a-z][a-z-]*)([^;`#]*)", code):
                yield f"{page.relative_to(ROOT)}:{number}", match.group(1), match.group(2)


MENTIONS = list(_mentions())


def test_the_pages_name_many_commands():
    """The parsing below finds what it checks (an empty list would pass everything)."""
    assert len(MENTIONS) > 60 and {c for _, c, _ in MENTIONS} >= set(COMMANDS)


def test_every_command_and_option_named_exists():
    wrong = []
    for where, command, rest in MENTIONS:
        if command not in COMMANDS:
            wrong.append(f"{where}: parcosim {command}")
            continue
        options = _options(command)
        tokens = rest.replace("[", " ").replace("]", " ").replace("=", " ").split()
        for option, value in itertools.zip_longest(tokens, tokens[1:]):
            if not option.startswith("--"):
                continue
            if option not in options:
                wrong.append(f"{where}: parcosim {command} {option}")
            elif options[option].choices and value and re.fullmatch(r"[a-z][a-z_-]*(\|[a-z][a-z_-]*)*", value):
                wrong += [f"{where}: parcosim {command} {option} {v}" for v in value.split("|")
                          if v not in options[option].choices]
    assert not wrong, wrong


#: Files of other projects that docs/ssp_tools.md cites by their own paths.
OTHER_PROJECTS = {"docs/user/file_formats.rst", "docs/user_guide/cosimulation_initialization.md",
                  "docs/user_guide/configuration_file.md"}


def _repository_paths():
    """(where, path) of every path of the repository named in code; a dated note may name a file
    that is gone if it says so right after it ("`controller/fastlaw.py` (gone since issue 27)")."""
    for page in PAGES:
        text = page.read_text(encoding="utf-8")
        lines = text.splitlines()
        for number, code in _code(text):
            for token in code.split():
                token = token.strip("(),;:.'\"").split(":")[0]
                if "/" not in token or not re.fullmatch(r"[\w.*{},/-]+", token) or token.startswith(OUTPUT_PREFIXES):
                    continue
                if token.split("/")[0] not in TOP_LEVEL or "//" in token or token in OTHER_PROJECTS:
                    continue
                if re.search(re.escape(token) + r"`?[^`]{0,40}\bgone\b", lines[number - 1]):
                    continue
                yield f"{page.relative_to(ROOT)}:{number}", token
        for number, line in enumerate(lines, 1):     # the pages also name each other in plain text
            for token in re.findall(r"(?<![\w/.-])docs/[\w-]+\.(?:md|png|csv|json)", line):
                yield f"{page.relative_to(ROOT)}:{number}", token


TOP_LEVEL = {p.name for p in ROOT.iterdir() if not p.name.startswith(".")} - {"out"}


def _exists(path: str) -> bool:
    braces = re.search(r"\{([^}]*)\}", path)
    if braces:
        return all(_exists(path[:braces.start()] + choice + path[braces.end():])
                   for choice in braces.group(1).split(","))
    if "*" in path:
        return any(ROOT.glob(path.rstrip("/")))
    return (ROOT / path).exists() or (ROOT / f"{path}.py").exists()      # `plant/__init__`: a module


def test_every_repository_path_named_exists():
    named = list(_repository_paths())
    assert len(named) > 100
    missing = [f"{where}: {path}" for where, path in named if not _exists(path)]
    assert not missing, missing


def test_every_python_module_named_exists():
    modules = {(f"{page.relative_to(ROOT)}", m) for page in PAGES
               for m in re.findall(r"python -m ([\w.]+)", page.read_text(encoding="utf-8"))}
    assert len(modules) > 5
    missing = [f"{where}: {m}" for where, m in modules if importlib.util.find_spec(m) is None]
    assert not missing, missing


def _stated_defaults():
    """(command, option, stated default) of every row of docs/index.md's option tables."""
    command = None
    for line in (ROOT / "docs" / "index.md").read_text(encoding="utf-8").splitlines():
        heading = re.match(r"`parcosim ([a-z-]+)", line)
        if heading:
            command = heading.group(1)
        row = re.match(r"\| `([^`]+)` \| (default: [^|]+|required) \|", line.replace("\\|", "/"))
        if row:
            words = row.group(1).split()
            if words[0] == "parcosim":
                command, words = words[1], words[2:]
            yield command, words[0], row.group(2).removeprefix("default: ").strip()


def _matches(action, stated: str) -> bool:
    """Whether ``stated`` is what the parser does when the option is not given."""
    if stated == "required":
        return action.required
    if action.default is None or action.default == []:
        # None: the command decides; the option's help must say the same.
        return stated == "none" or f"(default: {stated})" in " ".join(action.help.split())
    if action.default is False:
        return stated == "off"
    if isinstance(action.default, float):
        return float(stated) == pytest.approx(action.default, rel=1e-5)
    return str(action.default).rstrip("/") == stated.rstrip("/")


def test_the_reference_states_the_parsers_defaults():
    stated = list(_stated_defaults())
    assert len(stated) >= 35
    wrong = [f"parcosim {c} {o}: docs/index.md says {s!r}" + (
        f", the parser {_options(c)[o].default!r}" if o in _options(c) else ", the parser has no such option")
             for c, o, s in stated if o not in _options(c) or not _matches(_options(c)[o], s)]
    assert not wrong, wrong
    documented = {(c, o) for c, o, _ in stated}
    every = {(c, a.option_strings[0]) for c in COMMANDS for a in COMMANDS[c]._actions
             if a.option_strings and not isinstance(a, argparse._HelpAction)}
    assert every <= documented, sorted(every - documented)


def test_every_help_default_is_the_parsers():
    """A help text's "(default: X)" matches the parser's default when the parser has one."""
    wrong = []
    for command, parser in COMMANDS.items():
        for action in parser._actions:
            said = re.search(r"\(default:? ([^)]+)\)", " ".join((action.help or "").split()))
            if said and action.default not in (None, [], False) and not _matches(action, said.group(1)):
                wrong.append(f"parcosim {command} {action.option_strings or action.dest}: {said.group(0)}")
    assert not wrong, wrong
