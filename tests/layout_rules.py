"""Where a test file goes: ``tests/`` holds one folder per product layer (docs/layout.md).

A test file's folder is given by its name: :data:`RULES` is a list of (pattern, folder), the
first pattern (:func:`fnmatch.fnmatch` on the file name) that matches gives the folder.  A new
file whose name no rule matches is an error (``tests/repo/test_tests_layout.py`` fails): add a
rule, by prefix where the layer has one.

    python tests/layout_rules.py            # the misplaced test files, exit 1 if any
    python tests/layout_rules.py --move     # git mv each one to its folder (and list them)

A moved file is a module one or more packages deeper: an import of it (``tests.test_x``) or a
path built from its ``__file__`` must follow (:data:`tests.support.paths.ROOT` is the
repository, whatever the depth).
"""
from __future__ import annotations

import argparse
import subprocess
import sys
from fnmatch import fnmatch
from pathlib import Path

TESTS = Path(__file__).resolve().parent
ROOT = TESTS.parent
#: Folders of tests/ that hold no test files of a layer.
NOT_LAYERS = ("support", "native_host", "data")

#: (file-name pattern, folder under tests/), first match wins: the most specific patterns first.
RULES = [
    # kernels: the C steps, their bindings and builds
    ("test_kernels_*.py", "kernels"),
    ("test_oracles_kernels.py", "kernels"),
    ("test_fastkernels.py", "kernels"),
    ("test_sanitizers.py", "kernels"),
    ("test_refusal_record.py", "kernels"),
    # motor: the drive, current loop, observer, friction, identification
    ("test_motor_*.py", "motor"),
    ("test_oracles_drive.py", "motor"),
    ("test_friction*.py", "motor"),
    # plant: serial chains, the 5R, the wheeled pendulum, specs, the independent references
    ("test_wheeled_fmu*.py", "fmus/slaves"),
    ("test_wheeled*.py", "plant"),
    ("test_plant_*.py", "plant"),
    ("test_spec*.py", "plant"),
    ("test_reference_lagrange*.py", "plant"),
    ("test_serial*.py", "plant"),
    ("test_fivebar*.py", "plant"),
    ("test_balanced*.py", "plant"),
    ("test_actuated*.py", "plant"),
    ("test_correction*.py", "plant"),
    ("test_thesis_tables*.py", "plant"),
    # controller: derivators, trajectories, the laws and their designs
    ("test_controller*.py", "controller"),
    ("test_control_*.py", "controller"),
    ("test_derivator*.py", "controller"),
    ("test_trajector*.py", "controller"),
    ("test_seed_law*.py", "controller"),
    ("test_oracles_designs.py", "controller"),
    ("test_delay*.py", "controller"),
    # fmus/slave: the slave base and what every slave shares (refusals, sampling, budget, state)
    ("test_fmu_state*.py", "fmus/slave"),
    ("test_fmu_isolation*.py", "fmus/export"),
    ("test_extremes.py", "fmus/slave"),
    ("test_parameter_extremes.py", "fmus/slave"),
    ("test_fmi_contract*.py", "fmus/slave"),
    ("test_guarded*.py", "fmus/slave"),
    ("test_call_limits*.py", "fmus/slave"),
    ("test_sampling*.py", "fmus/slave"),
    ("test_refusals*.py", "fmus/slave"),
    # fmus/slaves: each model's FMU through fmpy
    ("test_fmu_*.py", "fmus/slaves"),
    ("test_slaves_*.py", "fmus/slaves"),
    ("test_sample_time_*.py", "fmus/slaves"),
    ("test_internal_observer*.py", "fmus/slaves"),
    ("test_drive_twin*.py", "fmus/slaves"),
    # fmus/export: FMU files, the C wrapper, what an FMU carries
    ("test_wrapper*.py", "fmus/export"),
    ("test_oracles_export.py", "fmus/export"),
    ("test_model_description*.py", "fmus/export"),
    ("test_cold_start*.py", "fmus/export"),
    ("test_precompute*.py", "fmus/export"),
    ("test_initial_outputs*.py", "fmus/export"),
    # fmus/native, fmus/cosim, fmus/systemfmu, fmus/ssp, fmus/hostile
    ("test_native_*.py", "fmus/native"),
    ("test_master*.py", "fmus/cosim"),
    ("test_compiled*.py", "fmus/cosim"),
    ("test_stepper*.py", "fmus/cosim"),
    ("test_inprocess*.py", "fmus/cosim"),
    ("test_foreign*.py", "fmus/cosim"),
    ("test_rate_groups*.py", "fmus/cosim"),
    ("test_system_*.py", "fmus/cosim"),
    ("test_status*.py", "fmus/cosim"),
    ("test_export_fmu*.py", "fmus/systemfmu"),
    ("test_embedded*.py", "fmus/systemfmu"),
    ("test_ssp*.py", "fmus/ssp"),
    ("test_libcosim*.py", "fmus/ssp"),
    ("test_hostile*.py", "fmus/hostile"),
    # scenarios: scenes, running one, batch work, packaging, studies
    ("test_scenes*.py", "scenarios/scenes"),
    ("test_vertical*.py", "scenarios/scenes"),
    ("test_pendulum_scene*.py", "scenarios/scenes"),
    ("test_perturb*.py", "scenarios/scenes"),
    ("test_transforms*.py", "scenarios/scenes"),
    ("test_contour*.py", "scenarios/run"),
    ("test_settling*.py", "scenarios/run"),
    ("test_metrics*.py", "scenarios/run"),
    ("test_run_*.py", "scenarios/run"),
    ("test_reference_*.py", "scenarios/run"),
    ("test_sweep*.py", "scenarios/batch"),
    ("test_engine*.py", "scenarios/batch"),
    ("test_worker_path*.py", "scenarios/batch"),
    ("test_regression*.py", "scenarios/batch"),
    ("test_report*.py", "scenarios/batch"),
    ("test_package*.py", "scenarios/packaging"),
    ("test_per_component*.py", "scenarios/packaging"),
    ("test_swap_*.py", "scenarios/packaging"),
    ("test_twin_linear_margin*.py", "benchmarks"),
    ("test_jacobi_delay_margin*.py", "benchmarks"),
    ("test_trade*.py", "scenarios/studies"),
    ("test_twin*.py", "scenarios/studies"),
    ("test_workspace*.py", "scenarios/studies"),
    ("test_tools*.py", "scenarios/studies"),
    ("test_balancing*.py", "scenarios/studies"),
    ("test_pendulum_trade*.py", "scenarios/studies"),
    ("test_robustness*.py", "scenarios/studies"),
    ("test_module_help*.py", "scenarios/studies"),
    ("test_example_*.py", "scenarios/examples"),
    # the command line
    ("test_cli_*.py", "cli"),
    # benchmarks/ and the mutation tools
    ("test_mutation_*.py", "benchmarks"),
    ("test_bench_*.py", "benchmarks"),
    ("test_memory*.py", "benchmarks"),
    ("test_mujoco_model*.py", "benchmarks"),
    ("test_profile_members*.py", "benchmarks"),
    ("test_machine_probe*.py", "benchmarks"),
    ("test_side_by_side*.py", "benchmarks"),
    # the repository as a whole: the product's layers, the docs' names, this layout
    ("test_layout.py", "repo"),
    ("test_docs_*.py", "repo"),
    ("test_tests_layout.py", "repo"),
    ("test_lazy_names.py", "repo"),
]


def folder_of(name: str) -> str:
    """The folder under tests/ of the test file called ``name`` (``test_x.py``).

    Raises
    ------
    LookupError
        When no rule of :data:`RULES` matches ``name``.
    """
    for pattern, folder in RULES:
        if fnmatch(name, pattern):
            return folder
    raise LookupError(f"no rule of tests/layout_rules.py gives a folder for {name}: add one to RULES")


def path_of(name: str) -> str:
    """``tests/FOLDER/NAME`` of the test file called ``name`` (``.py`` added when missing)."""
    name = name if name.endswith(".py") else f"{name}.py"
    return f"tests/{folder_of(name)}/{name}"


def test_files(tests: Path = TESTS) -> list:
    """Every ``test_*.py`` under ``tests``, outside the helpers' folders."""
    return sorted(p for p in tests.rglob("test_*.py")
                  if p.relative_to(tests).parts[0] not in NOT_LAYERS)


def misplaced(tests: Path = TESTS) -> list:
    """(file, wanted path relative to ``tests``' parent) of each test file not where its rule
    puts it; a file that no rule matches has ``None`` as wanted path."""
    found = []
    for path in test_files(tests):
        try:
            wanted = tests / folder_of(path.name) / path.name
        except LookupError:
            found.append((path, None))
            continue
        if path != wanted:
            found.append((path, wanted))
    return found


def packages(folder: Path, tests: Path = TESTS) -> list:
    """The ``__init__.py`` files from ``tests`` down to ``folder`` that do not exist yet."""
    missing, here = [], tests
    for part in folder.relative_to(tests).parts:
        here = here / part
        if not (here / "__init__.py").exists():
            missing.append(here / "__init__.py")
    return missing


def move(tests: Path = TESTS) -> list:
    """``git mv`` each misplaced test file to its folder (creating the folder as a package, with
    ``git add`` of its ``__init__.py``); return the (old, new) paths moved.

    Raises
    ------
    LookupError
        When a test file matches no rule (nothing is moved).
    """
    found = misplaced(tests)
    orphans = [str(p.relative_to(tests.parent)) for p, wanted in found if wanted is None]
    if orphans:
        raise LookupError(f"no rule of tests/layout_rules.py gives a folder for {', '.join(orphans)}")
    moved = []
    for path, wanted in found:
        for init in packages(wanted.parent, tests):
            init.parent.mkdir(parents=True, exist_ok=True)
            init.write_text(f'"""Tests of {init.parent.relative_to(tests)}/ (tests/layout_rules.py)."""\n')
            subprocess.run(["git", "add", str(init)], cwd=tests.parent, check=True)
        subprocess.run(["git", "mv", str(path), str(wanted)], cwd=tests.parent, check=True)
        moved.append((path.relative_to(tests.parent), wanted.relative_to(tests.parent)))
    return moved


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description="Test files not in the folder tests/layout_rules.py gives them.")
    parser.add_argument("--move", action="store_true", help="git mv each misplaced file to its folder")
    args = parser.parse_args(argv)
    if args.move:
        try:
            moved = move()
        except LookupError as error:
            print(error)
            return 2
        for old, new in moved:
            print(f"{old} -> {new}")
        if moved:
            print("now fix what names the old paths: imports tests.test_x, paths from __file__, docs")
        return 0
    found = misplaced()
    for path, wanted in found:
        where = "no rule" if wanted is None else wanted.relative_to(ROOT)
        print(f"{path.relative_to(ROOT)}: {where}")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
