"""Every command, option, choice and repository path the README and docs/ name exists, and every
default docs/index.md states is the parser's (issue 29, item 4).

Catches: an option renamed or removed without the docs (``parcosim run --coupling`` still
documented after a rename), a file moved or deleted that a page still points at, a default
changed in the parser but not in the reference, a help text whose "(default: X)" lies.
"""
from __future__ import annotations

import argparse
import ast
import importlib.util
import itertools
import re
import subprocess
from pathlib import Path

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
    """Catches a page naming a command, an option or a choice the parser does not have (renamed or removed
    without the docs)."""
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
    """Catches a page pointing at a file that moved or was deleted."""
    named = list(_repository_paths())
    assert len(named) > 100
    missing = [f"{where}: {path}" for where, path in named if not _exists(path)]
    assert not missing, missing


def test_every_python_module_named_exists():
    """Catches a page's python -m command whose module no longer exists."""
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


def _module_options(module: str) -> set:
    """The option strings ``python -m MODULE`` declares: every string starting with "-" given to an
    ``add_argument`` call in its source (read, not run: some modules' ``main`` works before parsing)."""
    path = Path(importlib.util.find_spec(module).origin)
    if path.name == "__init__.py" and (path.parent / "__main__.py").exists():
        path = path.parent / "__main__.py"
    return {a.value for node in ast.walk(ast.parse(path.read_text(encoding="utf-8")))
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "add_argument"
            for a in node.args if isinstance(a, ast.Constant) and isinstance(a.value, str) and a.value.startswith("-")}


def test_every_option_of_a_python_module_named_exists():
    """Catches a page naming an option of a ``python -m`` command that its parser no longer has
    (``python -m scenarios.tools --stop-time``, removed in session 35, was still in
    docs/contract.md); ``python -m parcosim`` is the parcosim command checked above, and other
    projects' modules (``python -m pytest``) are theirs."""
    named = [(f"{page.relative_to(ROOT)}:{number}", m.group(1), option)
             for page in PAGES for number, code in _code(page.read_text(encoding="utf-8"))
             for m in re.finditer(r"(?:^|[\s(|])python -m ([\w.]+)([^;`#|]*)", code) if m.group(1) != "parcosim"
             and (ROOT / m.group(1).split(".")[0]).is_dir()     # ours, not pytest's or fmpy's
             for option in re.findall(r"(?<![\w-])--[a-z][\w-]*", m.group(2))]
    assert len(named) > 50
    declared = {module: _module_options(module) for module in {m for _, m, _ in named}}
    wrong = [f"{where}: python -m {module} {option}" for where, module, option in named
             if option not in declared[module]]
    assert not wrong, wrong


def test_the_reference_states_the_parsers_defaults():
    """Catches docs/index.md stating a default the parser does not have, or an option it does not list at
    all."""
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


# --- defaults stated in prose, on any page ----------------------------------------------------

#: A program in code: ``parcosim COMMAND`` or ``python -m MODULE``.
_PROGRAM = re.compile(r"(?:^|[\s(|`])(parcosim [a-z][a-z-]*|python -m [\w.]+)")
#: "`PROGRAM ... --opt ...` (default `X`", the option the span's last.
_IN_SPAN = re.compile(r"`([^`]*--[a-z][\w-]*[^`]*)` \(default:? `?([^`;)]+?)`?[;)]")
#: "`--opt`, default `X`", "`--opt` defaults to X", "`--opt X` (default: X)".
_AFTER_OPTION = re.compile(r"`(--[a-z][\w-]*)(?: [^`]*)?`(?:,| \()? ?defaults?(?: to|:)? (?:`([^`]+)`|([^`\s,;)]+))")


class _Parsed(Exception):
    """Raised by :func:`_parser_of`'s patched ``parse_args`` with the parser it was called on."""

    def __init__(self, parser):
        super().__init__()
        self.parser = parser


def _parser_of(program: str, monkeypatch) -> argparse.ArgumentParser:
    """The parser of ``parcosim COMMAND`` or of ``python -m MODULE`` (its ``main`` stopped at
    its ``parse_args``)."""
    if program.startswith("parcosim "):
        return COMMANDS[program.split()[1]]
    module = importlib.import_module(program.split()[-1])
    source = Path(module.__file__).read_text(encoding="utf-8")
    # main([]) would run the module's work if nothing stopped it: only a main that parses first
    assert "ArgumentParser(" in source and ".parse_args(argv)" in source, f"{program}: no argparse main"

    def parse_args(self, *args, **kwargs):
        raise _Parsed(self)

    with monkeypatch.context() as patch:
        patch.setattr(argparse.ArgumentParser, "parse_args", parse_args)
        with pytest.raises(_Parsed) as parsed:
            module.main([])
    return parsed.value.parser


def _prose_defaults():
    """(where, program, option, stated default) of every default a page states in prose (the
    option tables of docs/index.md are :func:`_stated_defaults`), each paragraph's lines joined;
    the program is the span's own or the last one named before the option in its paragraph."""
    for page in PAGES:
        text = page.read_text(encoding="utf-8")
        for paragraph in re.split(r"\n\s*\n", text):
            if paragraph.lstrip().startswith("|") and page.name == "index.md":
                continue
            joined = " ".join(paragraph.split())
            line = text.count("\n", 0, text.find(paragraph.split("\n")[0])) + 1
            for match in _IN_SPAN.finditer(joined):
                programs = _PROGRAM.findall(" " + match.group(1))
                if programs:
                    option = re.findall(r"--[a-z][\w-]*", match.group(1))[-1]
                    yield f"{page.relative_to(ROOT)}:{line}", programs[-1], option, match.group(2)
            for match in _AFTER_OPTION.finditer(joined):
                programs = _PROGRAM.findall(joined[:match.start()])
                if programs:
                    yield f"{page.relative_to(ROOT)}:{line}", programs[-1], match.group(1), _value(match)


def _value(match) -> str:
    """The default an :data:`_AFTER_OPTION` match states: in backticks, or a word (without the
    sentence's full stop)."""
    return match.group(2) or match.group(3).rstrip(".")


def _says(action, stated: str) -> bool:
    """Whether ``stated`` is the parser's default, or, for an option the command decides
    (None), what its help says it decides."""
    if action.default is None:
        return stated.rstrip("/") in " ".join((action.help or "").split())
    if isinstance(action.default, str) and action.default.startswith(f"{ROOT}/"):   # a path of the repository
        return action.default.removeprefix(f"{ROOT}/").rstrip("/") == stated.rstrip("/")
    return _matches(action, stated)


def test_every_default_stated_in_prose_is_the_parsers(monkeypatch):
    """Catches a default changed in a parser (``python -m scenarios.tools --results``,
    ``benchmarks.mutation_py --seed``, ``parcosim build --out``) while a page still states
    the old one outside docs/index.md's tables."""
    stated = list(_prose_defaults())
    assert len(stated) >= 4, stated
    wrong = []
    for where, program, option, value in stated:
        options = {s: a for a in _parser_of(program, monkeypatch)._actions for s in a.option_strings}
        if option not in options or not _says(options[option], value):
            wrong.append(f"{where}: {program} {option}: the page says {value!r}, the parser "
                         + (repr(options[option].default) if option in options else "has no such option"))
    assert not wrong, wrong


def test_the_prose_default_reader_finds_each_form(monkeypatch):
    """Catches a prose-default reader that finds nothing (the check above would pass vacuously): each
    way the pages state a default is found, and a wrong default is reported."""
    forms = {"`parcosim build [--out DIR]` (default `fmus/build/`; more)": ("parcosim build", "--out", "fmus/build/"),
             "`python -m benchmarks.mutation_py`: `--seed` defaults to 3501; and":
                 ("python -m benchmarks.mutation_py", "--seed", "3501"),
             "`python -m scenarios.tools [--results F]`: resumable (`--results`, default `x/y.json`); more":
                 ("python -m scenarios.tools", "--results", "x/y.json")}
    for text, expected in forms.items():
        spans = [(p, o, v) for m in _IN_SPAN.finditer(text) for p in _PROGRAM.findall(" " + m.group(1))[-1:]
                 for o in re.findall(r"--[a-z][\w-]*", m.group(1))[-1:] for v in [m.group(2)]]
        after = [(_PROGRAM.findall(text[:m.start()])[-1], m.group(1), _value(m)) for m in _AFTER_OPTION.finditer(text)]
        assert expected in spans + after, (text, spans, after)
    seed = {s: a for a in _parser_of("python -m benchmarks.mutation_py", monkeypatch)._actions for s in a.option_strings}
    assert _says(seed["--seed"], "3501") and not _says(seed["--seed"], "3401")


# --- the notes: listed, stamped ---------------------------------------------------------------

#: A commit hash (7 to 40 hex digits, at least one a digit: not a word such as "defaced").
_COMMIT = re.compile(r"(?<![\w/.-])(?=[0-9a-f]*\d)[0-9a-f]{7,40}(?![\w/-])")


def _notes_table() -> dict:
    """Note -> the commit docs/index.md's "The notes" table gives it."""
    text = (ROOT / "docs" / "index.md").read_text(encoding="utf-8").split("## The notes", 1)[1]
    rows = re.findall(r"^\| (docs/[\w-]+\.md) \|[^\n]*\| ([^|]*) \|$", text, flags=re.M)
    return {note: next(iter(_COMMIT.findall(commit)), None) for note, commit in rows}


def _stamps(note: str) -> list:
    """The commits a note names in its first 20 lines (its header, or a generated page's fit line)."""
    return _COMMIT.findall("\n".join((ROOT / note).read_text(encoding="utf-8").splitlines()[:20]))


def test_every_note_is_listed_and_stamped_with_a_commit_of_the_history():
    """Catches a note added to docs/ without the commit its figures describe, or left out of
    docs/index.md's list of notes, and a stamp naming a commit that is not in the history (a
    typo, a hash of a branch that was never merged)."""
    table = _notes_table()
    notes = {f"docs/{p.name}" for p in (ROOT / "docs").glob("*.md")} - {"docs/index.md"}
    assert len(table) >= 25 and not notes - set(table), sorted(notes - set(table))
    assert all(table.values()), [n for n, c in table.items() if not c]
    unstamped = sorted(n for n in notes if not _stamps(n))
    assert not unstamped, unstamped
    if not (ROOT / ".git").exists():     # an exported tree: no history to look the commits up in
        return
    named = set(table.values()) | {c for n in notes for c in _stamps(n)}
    unknown = sorted(c for c in named if subprocess.run(["git", "cat-file", "-e", f"{c}^{{commit}}"], cwd=ROOT,
                                                        capture_output=True).returncode != 0)
    assert not unknown, unknown


def test_the_commit_reader_tells_a_hash_from_a_word():
    """Catches a stamp reader that misses hashes (the check above would pass vacuously) or takes words
    of hex letters, a hex name inside a path or a date for one."""
    assert _COMMIT.findall("commit `98328dc` (2026-12-03); full 0824d9d1f2e3a4b5c6d7e8f9a0b1c2d3e4f5a6b7") == [
        "98328dc", "0824d9d1f2e3a4b5c6d7e8f9a0b1c2d3e4f5a6b7"]
    assert _COMMIT.findall("defaced effaced fmus/build/a1b2c3d4 2026-12-03") == []
