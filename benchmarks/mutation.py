"""Mutation campaign (cosmic-ray) on the model code: plant/, motor/, controller/, fmus/slaves/.

    python -m benchmarks.mutation [--workdir out/mutation] [--sample 300] [--seed 18]
    python -m benchmarks.mutation --report                # figures and survivors so far
    python -m benchmarks.mutation --retest survived [--job ID ...]   # re-run survivors (after new tests)

Resumable: each source file is one cosmic-ray session (``WORKDIR/<file>.sqlite``); a run
executes the pending mutants only, so an interrupted campaign goes on where it stopped; a
file that changed since its session was made gets a new one (digests in ``sources.json``).
Run it in a detached worktree (it edits the source files in place, one mutant at a time):

    git worktree add --detach /work/wtDrun mutation18
    cd /work/wtDrun && nohup nice -n 10 env PYTHONPATH=$PWD python -m benchmarks.mutation > out/mutation.log 2>&1 &

What runs (docs/mutation.md):

* every mutant of the control law (:data:`LAW`: the sliding variable (7.22), the integral of
  (7.21), the adaptive gain (6.66), sat and sign; empty since the law is C (kernels/src/law.c),
  which this Python tool does not mutate);
* a seeded sample of :data:`SAMPLE` others, drawn uniformly from all other mutants of
  :data:`TARGETS`; the rest are marked ``skipped`` in their session.

The C kernels (kernels/src/) are not mutated by this tool.  Each mutant runs only the test modules of its file
(:data:`TARGETS`), stopping at the first failure.  Replacements by a bitwise operator
(``>> << | & ^``) are left out: on the float operands of this code they raise TypeError at the
first call, which tells nothing about the tests.
"""
from __future__ import annotations

import argparse
import ast
import hashlib
import json
import os
import random
import sqlite3
import subprocess
import sys
from pathlib import Path

from tests.layout_rules import path_of

ROOT = Path(__file__).resolve().parent.parent

_CTRL = ("test_control_law", "test_seed_law", "test_controller", "test_kernels_law")
_PLANT = ("test_plant_dynamics", "test_fivebar", "test_reference_lagrange")
_WHEELED = ("test_wheeled", "test_wheeled_derivation", "test_wheeled_fmu")
#: Source file -> the test modules that exercise it (run in this order, -x).
TARGETS = {
    "controller/law.py": _CTRL,
    "controller/position.py": _CTRL + ("test_fmu_controller",),
    "controller/strategies.py": ("test_thesis_tables", "test_control_law", "test_controller"),
    "controller/kinematics.py": ("test_controller_kinematics", "test_controller"),
    "controller/model.py": ("test_controller_model", "test_controller"),
    "controller/derivators.py": ("test_derivators",),
    "controller/trajectories.py": ("test_trajectories", "test_thesis_tables"),
    "plant/serial.py": ("test_serial",) + _PLANT,
    "plant/parallel.py": _PLANT,
    "plant/fivebar.py": ("test_fivebar", "test_plant_dynamics", "test_controller_kinematics"),
    "plant/fast5r.py": _PLANT + ("test_controller_model", "test_compiled"),  # ExactModel's kernel; the scene loop
    "plant/simulator.py": ("test_plant_dynamics", "test_fmu_plant"),
    "plant/integrators.py": ("test_plant_dynamics",),
    "plant/correction.py": ("test_correction",),
    "plant/actuated.py": ("test_actuated",),
    "plant/presets.py": ("test_thesis_tables", "test_balanced", "test_plant_dynamics"),   # counter_offsets: seed 001 (64)
    "motor/electrics.py": ("test_motor_electrics", "test_motor_current_control"),
    "motor/current_controller.py": ("test_motor_current_control",),
    # LuGre drives step through test_friction and test_drive_twin; the Euler divergence hint through
    # one test of test_extremes
    "motor/drive.py": ("test_motor_current_control", "test_motor_electrics", "test_fmu_motor", "test_actuated",
                       "test_friction", "test_drive_twin",
                       "test_extremes::test_explicit_euler_drive_alone_refuses_a_non_finite_current"),
    "motor/observer.py": ("test_motor_observer",),
    "motor/identification.py": ("test_motor_identification",),
    "motor/presets.py": ("test_thesis_tables", "test_motor_presets"),
    "motor/_checks.py": ("test_motor_electrics", "test_motor_current_control"),
    "motor/friction.py": ("test_friction", "test_drive_twin"),     # LuGre (item 2 of issue 18), added after the campaign
    "fmus/slaves/parcosim_positioncontroller.py": ("test_fmu_controller",),
    "fmus/slaves/parcosim_dcmotordrive.py": ("test_fmu_motor",),
    "fmus/slaves/parcosim_currentobserver.py": ("test_fmu_motor",),
    "fmus/slaves/parcosim_fivebarplant.py": ("test_fmu_plant",),
    "fmus/slaves/parcosim_derivator.py": ("test_fmu_controller",),
    "fmus/slaves/parcosim_trajectory.py": ("test_fmu_controller",),
    "fmus/slaves/parcosim_actuatedfivebarplant.py": ("test_actuated",),
    "controller/balance.py": ("test_wheeled_fmu", "test_fastkernels", "test_wheeled"),
    "controller/fastbalance.py": ("test_fastkernels", "test_wheeled_fmu"),
    "controller/fastderivator.py": ("test_fastkernels", "test_derivators", "test_compiled"),   # derivator_step: the scene loop
    "controller/fasttrajectory.py": ("test_fastkernels", "test_trajectories", "test_compiled"),
    "plant/spec.py": ("test_spec", "test_spec_plant", "test_workspace"),
    "plant/specsim.py": ("test_spec_plant", "test_spec", "test_workspace"),
    "plant/wheeled.py": _WHEELED,
    "plant/wheeled_kernel.py": _WHEELED,
    "fmus/slaves/parcosim_balancecontroller.py": ("test_wheeled_fmu",),
    "fmus/slaves/parcosim_specplant.py": ("test_spec_plant",),
    "fmus/slaves/parcosim_wheeledpendulum.py": ("test_wheeled_fmu",),
    # The FMU state and the call budget (issue 30; their first sample: benchmarks/mutation_state.py)
    "fmus/slave/state_format.py": ("test_fmu_state_data",),
    "fmus/slave/state.py": ("test_fmu_state_data", "test_fmu_state"),
    "fmus/slave/state_calls.py": ("test_fmu_state_data", "test_fmu_state"),
    "fmus/slave/budget.py": ("test_call_limits",),
}
#: The control law, whose every mutant runs: functions by name; "f:for" is the for loops in f.
#: Empty since the law is C (kernels/src/law.c), which this Python mutation tool does not mutate.
LAW = {}
SAMPLE = 300
SEED = 18
TIMEOUT = 180.0
GROUP_KEYS = ("mutants", "ran", "killed", "timeout", "survived", "incompetent", "pending")
EXCLUDED_OPERATORS = ("_RShift", "_LShift", "_BitOr", "_BitAnd", "_BitXor")


def _session(workdir: Path, source: str) -> Path:
    return workdir / (source.replace("/", "__").removesuffix(".py") + ".sqlite")


def _test_command(source: str) -> str:
    tests = " ".join(path_of(file) + sep + test for file, sep, test in (name.partition("::") for name in TARGETS[source]))
    return f"{sys.executable} -m pytest -x -q -p no:cacheprovider -o addopts= {tests}"


def _config(workdir: Path, source: str) -> Path:
    path = workdir / (source.replace("/", "__").removesuffix(".py") + ".toml")
    path.write_text(
        "[cosmic-ray]\n"
        f'module-path = "{source}"\n'
        f"timeout = {TIMEOUT}\n"
        "excluded-modules = []\n"
        f'test-command = "{_test_command(source)}"\n'
        "[cosmic-ray.distributor]\n"
        'name = "local"\n')
    return path


def _law_lines(source: str) -> set[int]:
    """Line numbers of the functions of :data:`LAW` in source."""
    tree = ast.parse((ROOT / source).read_text())
    lines = set()
    for node in ast.walk(tree):
        if not isinstance(node, ast.FunctionDef):
            continue
        if node.name in LAW.get(source, ()):
            lines.update(range(node.lineno, node.end_lineno + 1))
        elif f"{node.name}:for" in LAW.get(source, ()):
            for loop in ast.walk(node):
                if isinstance(loop, ast.For):
                    lines.update(range(loop.lineno, loop.end_lineno + 1))
    return lines


def _is_law(source, mutation, law_lines) -> bool:
    return mutation.start_pos[0] in law_lines.get(source, ())


def _digest(source: str) -> str:
    return hashlib.sha256((ROOT / source).read_bytes()).hexdigest()


def _init_sessions(workdir: Path) -> set:
    """Create the session of every source file that has none, and create again the session of
    every file that changed since its session was made (cosmic-ray names a mutant by module,
    operator and occurrence: an edit makes the old names point elsewhere).  The files' digests
    are kept in ``WORKDIR/sources.json``.  Returns the files whose session was (re)created."""
    manifest_path = workdir / "sources.json"
    manifest = json.loads(manifest_path.read_text()) if manifest_path.exists() else {}
    created = set()
    for source in TARGETS:
        session, digest = _session(workdir, source), _digest(source)
        config = _config(workdir, source)
        if session.exists() and manifest.get(source) == digest:
            continue
        if session.exists():
            print(f"{source} changed since its session was made: initialised again", flush=True)
            session.unlink()
        subprocess.run(["cosmic-ray", "init", str(config), str(session)], cwd=ROOT, check=True,
                       stdout=subprocess.DEVNULL)
        manifest[source] = digest
        created.add(source)
    manifest_path.write_text(json.dumps(manifest, indent=1, sort_keys=True))
    return created


def _quotas(pools: dict, sample: int) -> dict:
    """Largest-remainder share of ``sample`` per file, proportional to the file's pool."""
    total = sum(len(jobs) for jobs in pools.values())
    exact = {source: sample * len(jobs) / total for source, jobs in pools.items()}
    quotas = {source: int(value) for source, value in exact.items()}
    by_remainder = sorted(exact, key=lambda source: (quotas[source] - exact[source], source))
    for source in by_remainder[:sample - sum(quotas.values())]:
        quotas[source] += 1
    return quotas


def initialise(workdir: Path, sample: int, seed: int):
    """Create the sessions that are missing or stale, then draw the sample.

    The sample is stratified by file with the same rate everywhere: file f gets its
    largest-remainder share of ``sample`` in proportion to its pool (the mutants that are
    neither the law nor a bitwise operator).  A file whose session was kept keeps the mutants
    it already had in the sample (a uniform draw), trimmed or topped up to its share by a
    seeded uniform draw (``random.Random(f"{seed}:{file}")``); a new session draws its share
    afresh.  Every mutant of the pool thus has the same chance, and a source change costs only
    the changed files' results.  The draw is in ``WORKDIR/sample.json``."""
    from cosmic_ray.work_db import WorkDB, use_db
    from cosmic_ray.work_item import WorkerOutcome, WorkResult

    workdir.mkdir(parents=True, exist_ok=True)
    created = _init_sessions(workdir)
    marker = workdir / "sample.json"
    if marker.exists() and not created and json.loads(marker.read_text()).get("sample") == sample:
        return
    law_lines = {source: _law_lines(source) for source in LAW}
    pools, excluded, in_sample = {}, {}, {}
    for source in TARGETS:
        with use_db(str(_session(workdir, source)), WorkDB.Mode.open) as db:
            skipped = {job for job, result in db.results if result.worker_outcome == "skipped"}
            pools[source], excluded[source] = [], []
            for item in db.work_items:
                mutation = item.mutations[0]
                if mutation.operator_name.endswith(EXCLUDED_OPERATORS):
                    excluded[source].append(item.job_id)
                elif not _is_law(source, mutation, law_lines):
                    pools[source].append(item.job_id)
            pools[source].sort()
            in_sample[source] = [] if source in created else [job for job in pools[source] if job not in skipped]
    quotas = _quotas(pools, sample)
    drawn = {}
    for source, pool in pools.items():
        rng = random.Random(f"{seed}:{source}")
        kept = in_sample[source]
        if len(kept) > quotas[source]:
            kept = sorted(rng.sample(kept, quotas[source]))
        rest = sorted(set(pool) - set(kept))
        drawn[source] = sorted(kept + rng.sample(rest, quotas[source] - len(kept)))
        unsampled = sorted(set(pool) - set(drawn[source]))
        with use_db(str(_session(workdir, source)), WorkDB.Mode.open) as db:
            db.set_multiple_results(excluded[source] + unsampled,
                                    WorkResult(worker_outcome=WorkerOutcome.SKIPPED))
        with sqlite3.connect(_session(workdir, source)) as con:     # newly drawn: pending again
            con.executemany("DELETE FROM work_results WHERE job_id = ? AND worker_outcome = 'SKIPPED'",
                            [(job,) for job in drawn[source]])
    marker.write_text(json.dumps({
        "seed": seed, "sample": sample, "pool": sum(map(len, pools.values())),
        "files": {source: {"pool": len(pools[source]), "quota": quotas[source]} for source in pools},
        "sampled": sorted(f"{source}:{job}" for source, jobs in drawn.items() for job in jobs)}, indent=1))


def _restore_sources(workdir: Path):
    """A campaign killed mid-mutant leaves that mutant on disk: put the file under mutation
    (``WORKDIR/current.<worktree>``) back from git; files edited by hand are never touched."""
    marker = workdir / f"current.{ROOT.name}"
    if marker.exists():
        source = marker.read_text().strip()
        subprocess.run(["git", "checkout", "--", source], cwd=ROOT, check=True)
        marker.unlink()


def execute(workdir: Path, only=None):
    """Run the pending mutants, control law first."""
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    order = list(LAW) + [s for s in TARGETS if s not in LAW]
    _restore_sources(workdir)
    for source in order:
        if only and source not in only:
            continue
        if subprocess.run(["git", "diff", "--quiet", "--", source], cwd=ROOT).returncode:
            raise SystemExit(f"{source} differs from git: run the campaign in a clean detached worktree")
        print(f"== {source}", flush=True)
        (workdir / f"current.{ROOT.name}").write_text(source)
        subprocess.run(["cosmic-ray", "exec", str(_config(workdir, source)), str(_session(workdir, source))],
                       cwd=ROOT, env=env, check=False)
        _restore_sources(workdir)


def _hunk(diff: str) -> tuple:
    """The lines of a mutant's unified diff without its headers: context (" "), removed
    ("-") and added ("+"), stripped, blank ones left out (a removed decorator takes the
    blank lines above it along)."""
    return tuple(line[0] + line[1:].strip() for line in (diff or "").splitlines()
                 if line[:1] in " -+" and not line.startswith(("---", "+++")) and line[1:].strip())


def _changed_lines(hunk: tuple) -> tuple:
    """(removed lines, added lines) of a :func:`_hunk`."""
    return (tuple(line[1:] for line in hunk if line[0] == "-"), tuple(line[1:] for line in hunk if line[0] == "+"))


def _relocated(mutation, diff: str):
    """The mutation of the file as it is now that makes the change ``diff`` records, or None.

    cosmic-ray names a mutant by operator and occurrence, which an edit elsewhere in the file
    shifts: the mutant is found again by its text, among the occurrences of its operator in the
    same function whose line reads as the diff's first removed line and whose mutation
    removes and adds the same lines.  Several such (a repeated line): those whose diff has
    the same context lines too, then the recorded occurrence among them (an unchanged file).
    None when no occurrence, or more than one, is left (the code changed, or the line and its
    surroundings are repeated)."""
    import difflib

    import attrs
    import cosmic_ray.plugins
    from cosmic_ray.ast import ast_nodes, get_ast_from_path
    from cosmic_ray.ast.ast_query import ASTQuery
    from cosmic_ray.mutating import mutate_code

    hunk = _hunk(diff)
    wanted = _changed_lines(hunk)
    if not wanted[0]:
        return None
    operator = cosmic_ray.plugins.get_operator(mutation.operator_name)(**mutation.operator_args)
    path = ROOT / mutation.module_path
    code = path.read_text()
    lines = code.split("\n")
    positions = [(node, start, end) for node in ast_nodes(get_ast_from_path(path))
                 for start, end in operator.mutation_positions(node)]
    found, same_context = {}, {}
    for occurrence, (node, start, end) in enumerate(positions):
        if (lines[start[0] - 1].strip() != wanted[0][0]
                or ASTQuery(node).get_definition_name() != mutation.definition_name):
            continue
        mutated = mutate_code(code, operator, occurrence).split("\n")
        candidate = _hunk("\n".join(difflib.unified_diff(lines, mutated, lineterm="")))
        if _changed_lines(candidate) == wanted:
            found[occurrence] = attrs.evolve(mutation, occurrence=occurrence, start_pos=start, end_pos=end)
            if candidate == hunk:
                same_context[occurrence] = found[occurrence]
    if len(found) > 1:
        found = same_context
    if len(found) > 1 and mutation.occurrence in found:
        return found[mutation.occurrence]
    return next(iter(found.values())) if len(found) == 1 else None


def retest(workdir: Path, outcome: str, only=None, jobs=None):
    """Run again the mutants whose result has this test outcome (e.g. ``survived``, after new
    tests) and record the new result; the pending mutants are left alone; ``jobs``: these job
    ids only (e.g. not the survivors already argued equivalent).

    The sessions are used as they are, also for a file edited since its session was made
    (which a campaign run would make again, dropping its results): each mutant is found again
    in the file as it is now by its text (:func:`_relocated`).  A mutant whose line no longer
    reads as it did (the code was changed or removed) keeps its result and is listed as such."""
    from cosmic_ray.mutating import mutate_and_test
    from cosmic_ray.work_db import WorkDB, use_db

    os.environ.update(PYTHONPATH=str(ROOT))
    os.chdir(ROOT)
    _restore_sources(workdir)
    for source in TARGETS:
        if only and source not in only:
            continue
        session = _session(workdir, source)
        if not session.exists():
            raise SystemExit(f"{source}: no session in {workdir}")
        with use_db(str(session), WorkDB.Mode.open) as db:
            for item, result in db.completed_work_items:
                if result.test_outcome != outcome or (jobs and item.job_id not in jobs):
                    continue
                line = item.mutations[0].start_pos[0]
                mutation = _relocated(item.mutations[0], result.diff)
                if mutation is None:
                    print(f"{source}:{line} job {item.job_id}: the line changed, not re-run", flush=True)
                    continue
                (workdir / f"current.{ROOT.name}").write_text(source)
                new = mutate_and_test([mutation], _test_command(source), TIMEOUT)
                _restore_sources(workdir)
                db.set_result(item.job_id, new)
                moved = f" (now line {mutation.start_pos[0]})" if mutation.start_pos[0] != line else ""
                print(f"{source}:{line}{moved} job {item.job_id}: {new.test_outcome}", flush=True)


def report(workdir: Path) -> dict:
    """Counts per file and outcome, and the survivors with their diffs."""
    from cosmic_ray.work_db import WorkDB, use_db

    law_lines = {source: _law_lines(source) for source in LAW}
    rows, survivors = {}, []
    groups = {f"control law, {source}": dict.fromkeys(GROUP_KEYS, 0) for source in LAW}
    groups["seeded sample of the other mutants"] = dict.fromkeys(GROUP_KEYS, 0)
    for source in TARGETS:
        path = _session(workdir, source)
        if not path.exists():
            continue
        counts = {"mutants": 0, "law": 0, "skipped": 0, "pending": 0, "killed": 0, "timeout": 0,
                  "survived": 0, "incompetent": 0}
        with use_db(str(path), WorkDB.Mode.open) as db:
            results = dict(db.results)
            for item in db.work_items:
                counts["mutants"] += 1
                mutation = item.mutations[0]
                law = _is_law(source, mutation, law_lines)
                result = results.get(item.job_id)
                if result is None:
                    counts["pending"] += 1
                    groups[f"control law, {source}" if law else "seeded sample of the other mutants"]["pending"] += 1
                elif result.worker_outcome == "skipped":
                    counts["skipped"] += 1
                    continue
                else:
                    outcome = result.test_outcome
                    if outcome == "killed" and result.output == "timeout":
                        outcome = "timeout"
                    counts[outcome] += 1
                    group = groups[f"control law, {source}" if law else "seeded sample of the other mutants"]
                    group[outcome] += 1
                    group["ran"] += 1
                    if outcome == "survived":
                        survivors.append({"file": source, "line": mutation.start_pos[0], "job": item.job_id,
                                          "operator": mutation.operator_name, "law": law,
                                          "diff": result.diff})
                counts["law"] += law
        rows[source] = counts
    for group in groups.values():
        group["mutants"] = group["ran"] + group["pending"]
    return {"files": rows, "groups": groups, "survivors": survivors}


def print_report(data: dict):
    keys = ("mutants", "skipped", "pending", "killed", "timeout", "survived", "incompetent")
    print(f"{'file':46s}" + "".join(f"{k:>12s}" for k in keys))
    total = dict.fromkeys(keys, 0)
    for source, counts in data["files"].items():
        print(f"{source:46s}" + "".join(f"{counts[k]:12d}" for k in keys))
        for k in keys:
            total[k] += counts[k]
    print(f"{'total':46s}" + "".join(f"{total[k]:12d}" for k in keys))
    print(f"\n{'group':46s}" + "".join(f"{k:>12s}" for k in GROUP_KEYS))
    for name, counts in data["groups"].items():
        print(f"{name:46s}" + "".join(f"{counts[k]:12d}" for k in GROUP_KEYS))
    print(f"\n{len(data['survivors'])} survivors:")
    for s in data["survivors"]:
        diff = "\n".join(line for line in (s["diff"] or "").splitlines()
                         if line.startswith(("+", "-")) and not line.startswith(("+++", "---")))
        print(f"- {s['file']}:{s['line']} {s['operator']}{' (law)' if s['law'] else ''} job {s['job']}\n{diff}")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workdir", type=Path, default=ROOT / "out" / "mutation")
    parser.add_argument("--sample", type=int, default=SAMPLE)
    parser.add_argument("--seed", type=int, default=SEED)
    parser.add_argument("--only", nargs="*", help="run these source files only")
    parser.add_argument("--report", action="store_true", help="print the figures, run nothing")
    parser.add_argument("--retest", metavar="OUTCOME", help="run again the mutants with this outcome only")
    parser.add_argument("--job", nargs="*", help="with --retest: these job ids only")
    args = parser.parse_args(argv)
    if args.report:
        data = report(args.workdir)
        print_report(data)
        (args.workdir / "report.json").write_text(json.dumps(data, indent=1))
        return 0
    if args.retest:      # the sessions as they are: initialise would drop those of edited files
        retest(args.workdir, args.retest, args.only, args.job)
    else:
        initialise(args.workdir, args.sample, args.seed)
        execute(args.workdir, args.only)
    print_report(report(args.workdir))
    return 0


if __name__ == "__main__":
    sys.exit(main())
