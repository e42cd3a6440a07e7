"""fmus/hostile/cases.py without running a case (the campaign's own tests are of the slow kind):
the variable table read from a slave's model description, the cases a seed makes (what each
kind makes hostile and what it leaves sane), and the summary's counts (issue 31: the FMI layer's
weakest area, every value compared with what the docstrings say)."""
from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections import Counter

import pytest
from fmpy import read_model_description

from fmus.cosim.backends import InProcessInstance
from fmus.hostile.cases import (HOSTILE_REALS, KINDS, OUTCOMES, SANE_INPUTS, START_TIMES, STATE_VARIANTS,
                                STEP_SIZES, WRAPPER_KINDS, CaseResult, make_case, markdown_summary, summary, variable_table)

MODEL = "DCMotorDrive"


def _table(model, folder):
    slave = InProcessInstance(model, "d").slave
    path = folder / "modelDescription.xml"
    path.write_bytes(ET.tostring(slave.to_xml(), encoding="UTF-8", xml_declaration=True))
    return slave, variable_table(read_model_description(str(path)))


@pytest.fixture(scope="module")
def table(tmp_path_factory):
    return _table(MODEL, tmp_path_factory.mktemp("md"))


def test_the_variable_table_is_each_variables_name_type_causality_variability_and_start(table):
    """Catches a start parsed as another type (a Boolean "false" read as True, an Integer as a
    float), the causality and variability swapped, a variable left out."""
    slave, rows = table
    assert len(rows) == len(slave.vars)
    kinds = {"Real": float, "Integer": int, "Boolean": bool, "String": str}
    for (name, type_, causality, variability, start), variable in zip(rows, slave.vars.values()):
        assert name == variable.name and causality == variable.causality.name
        assert variability == (variable.variability.name if variable.variability else "continuous")
        if start is not None:
            assert type(start) is kinds[type_] and start == getattr(slave, name), name
    by_name = {row[0]: row for row in rows}
    assert by_name["internal_observer"][1:] == ("Boolean", "parameter", "fixed", False)
    assert by_name["T"][1:] == ("Real", "parameter", "fixed", 1e-3)
    assert by_name["sample_phase"][1:] == ("Integer", "parameter", "fixed", 0)
    assert by_name["i_ref"][2] == "input" and by_name["tau"][2] == "output"


def test_a_seed_makes_the_same_case_and_draws_no_wrapper_kind_unless_asked(table):
    """Catches cases that are not reproducible from their seed, the same case drawn for two models, or
    wrapper-only kinds drawn for pythonfmu's binary."""
    _, rows = table
    assert make_case(MODEL, rows, 17) == make_case(MODEL, rows, 17)
    plain = Counter(make_case(MODEL, rows, seed)["kind"] for seed in range(300))
    assert set(plain) == set(KINDS) - set(WRAPPER_KINDS)
    wrapped = Counter(make_case(MODEL, rows, seed, wrapper=True)["kind"] for seed in range(300))
    assert set(wrapped) == set(KINDS)
    assert make_case("Derivator", rows, 17) != make_case(MODEL, rows, 17)     # the model is in the seed


def test_each_kind_makes_hostile_what_it_is_about_and_keeps_the_rest_sane(table):
    """Catches a kind that sets parameters it should not, step sizes off the list or hostile
    where sane, a state case without its bytes or with the model's own state as foreign,
    start times off the list, the ``error`` output written."""
    _, rows = table
    parameters = {row[0] for row in rows if row[2] == "parameter"}
    for seed in range(120):
        case = make_case(MODEL, rows, seed, kind=KINDS[seed % len(KINDS)], wrapper=True,
                         models=("DCMotorDrive", "Derivator"))
        kind, ops = case["kind"], case["ops"]
        assert not any(op[0] == "set" and op[1] == "error" for op in ops)
        if kind not in ("parameters", "strings"):
            assert case["parameters"] == []
        else:
            assert {name for name, _ in case["parameters"]} <= parameters
        if kind == "parameters":
            assert 1 <= len(case["parameters"]) <= 3
        steps = [op for op in ops if op[0] == "step"]
        assert 1 <= len(steps) <= 6
        if kind == "steps":
            assert all(op[2] in STEP_SIZES or math.isnan(op[2]) for op in steps)
        else:
            assert all(op[2] == 1e-3 for op in steps)
        if kind != "order":
            assert all(op[1] is None for op in steps) and ops[0][0] != "step_before_init"
        states = [op for op in ops if op[0] == "state_bytes"]
        assert len(states) == (kind == "state")
        if states:
            assert states[0][1] in STATE_VARIANTS and states[0][3] == "Derivator" and 0 <= states[0][2] < 2 ** 31
        assert case["start_time"] in START_TIMES or math.isnan(case["start_time"])
        if kind != "start":
            assert case["start_time"] == 0.0
        if kind != "lifecycle":
            assert case["guid"] == "own"
        if kind == "inputs":
            values = [op[2] for op in ops if op[0] == "set"]
            assert values and all(isinstance(v, float) for v in values)
        if kind not in ("inputs", "sets"):
            for op in ops:
                if op[0] == "set":
                    assert op[2] not in HOSTILE_REALS[6:] and math.isfinite(op[2]), op


def test_the_summary_counts_each_outcome_per_fmu_and_kind_and_in_all():
    """Catches the campaign's summary miscounting an outcome per FMU and kind or in the "all" row, or
    ordering its table otherwise."""
    cases = [({"model": "A", "kind": "steps"}, "ok"), ({"model": "A", "kind": "steps"}, "refused"),
             ({"model": "A", "kind": "state"}, "refused"), ({"model": "B", "kind": "steps"}, "crash")]
    results = [CaseResult(case, outcome) for case, outcome in cases]
    table = summary(results)
    zero = dict.fromkeys(OUTCOMES, 0)
    assert table == {("A", "steps"): {**zero, "ok": 1, "refused": 1}, ("A", "all"): {**zero, "ok": 1, "refused": 2},
                     ("A", "state"): {**zero, "refused": 1}, ("B", "steps"): {**zero, "crash": 1},
                     ("B", "all"): {**zero, "crash": 1}}
    lines = markdown_summary(results).splitlines()
    assert lines[0] == "| FMU | kind | cases | ok | refused | fatal | violation | crash | hang |"
    assert lines[2:] == ["| A | **all** | 3 | 1 | 2 | 0 | 0 | 0 | 0 |", "| A | state | 1 | 0 | 1 | 0 | 0 | 0 | 0 |",
                         "| A | steps | 2 | 1 | 1 | 0 | 0 | 0 | 0 |", "| B | **all** | 1 | 0 | 0 | 0 | 0 | 1 | 0 |",
                         "| B | steps | 1 | 0 | 0 | 0 | 0 | 1 | 0 |"]


def test_the_summary_table_is_markdown_a_delimiter_cell_under_each_header_cell():
    """A markdown (GFM) table needs a delimiter row of as many cells as its header: catches the
    outcomes' columns left out of it (the table then renders as text)."""
    lines = markdown_summary([CaseResult({"model": "A", "kind": "steps"}, "ok")]).splitlines()
    header, delimiter = (line.strip("|").split("|") for line in lines[:2])
    assert len(header) == 3 + len(OUTCOMES) and len(delimiter) == len(header)
    assert all(cell.strip() == "---" for cell in delimiter)


def test_every_case_sets_each_real_input_near_its_sane_value_before_its_first_step(table, tmp_path):
    """In every case each Real input is set once before the first step, in the order of the
    variables, within 2 % (and 2e-4 absolute) of its sane value (:data:`SANE_INPUTS`, else
    its start); an "inputs" case sets them all again before every step (with hostile values),
    the others never again.  Catches the inputs set only in "inputs" cases (a case then
    steps an FMU with unset inputs), set before every step in every case, an input left out,
    and values drawn away from the sane pose."""
    cases = {MODEL: table[1], "PositionController": _table("PositionController", tmp_path)[1]}
    for model, rows in cases.items():
        inputs = {row[0]: row[4] for row in rows if row[2] == "input" and row[1] == "Real"}
        sane = {**inputs, **SANE_INPUTS.get(model, {})}
        for seed in range(90):
            case = make_case(model, rows, seed, kind=KINDS[seed % len(KINDS)], wrapper=True, models=(model,))
            intervals = [[]]       # the inputs set before each step, and after the last
            for op in case["ops"]:
                if op[0] == "step":
                    intervals.append([])
                elif op[0] == "set" and op[1] in inputs:
                    intervals[-1].append(op)
            assert intervals[-1] == [] and [op[1] for op in intervals[0]] == list(inputs), (model, seed)
            if case["kind"] == "inputs":
                assert all([op[1] for op in before] == list(inputs) for before in intervals[1:-1]), (model, seed)
                continue
            assert all(before == [] for before in intervals[1:-1]), (model, seed)
            for _, name, value in intervals[0]:
                base = sane[name]
                assert abs(value - base) <= 0.02 * abs(base) + 2e-4 * (abs(base) or 1.0) + 1e-15, (model, name, value)


def _sets_made(rows, seeds=200):
    """Counter of what the "sets" cases of ``seeds`` seeds write: "output", "parameter", "set_vr"."""
    causality = {row[0]: row[2] for row in rows}
    made = Counter()
    for seed in range(seeds):
        for op in make_case(MODEL, rows, seed, kind="sets")["ops"]:
            if op[0] == "set_vr":
                made["set_vr"] += 1
            elif op[0] == "set" and causality[op[1]] != "input":
                made[causality[op[1]]] += 1
    return made


def test_a_sets_case_writes_outputs_parameters_and_unknown_references_as_drawn(table):
    """Each of a "sets" case's 1-3 extra writes is an output (35 %), else a parameter (35 %),
    else a raw value reference (30 %); a model without outputs or parameters gets the others.
    Catches a kind of write never drawn (parameters written in place of the raw references),
    the shares off, or a model without parameters failing to make its case."""
    _, rows = table
    made = _sets_made(rows)
    total = sum(made.values())
    assert set(made) == {"output", "parameter", "set_vr"} and 200 <= total <= 600
    for what, share in (("output", 0.35), ("parameter", 0.35), ("set_vr", 0.30)):
        assert abs(made[what] / total - share) < 0.08, (what, made)
    bare = [row for row in rows if row[2] not in ("parameter", "output")]
    assert set(_sets_made(bare, 60)) == {"set_vr"}


def test_only_a_strings_case_names_its_instance_otherwise_and_it_draws_every_hostile_name(table):
    """A case's instance is named "instance" unless its kind is "strings", whose names are drawn from
    the five of :func:`make_case` (each drawn in 100 seeds).  Catches the hostile names given to the
    other kinds (an instance-name refusal then hides what the case is about) or never drawn."""
    _, rows = table
    names = ("instance", "%s%s%s%s%n", "é#%41", "a" * 300, "")
    for kind in KINDS:
        drawn = Counter(make_case(MODEL, rows, seed, kind=kind, wrapper=True)["instance_name"] for seed in range(100))
        assert set(drawn) == (set(names) if kind == "strings" else {"instance"}), (kind, drawn)


def test_an_order_case_steps_at_the_listed_wrong_points_after_the_time_it_reached(table):
    """Each communication point an "order" case names is one of 0, -1, t + 0.5, t - 1e-3, NaN, 1e300 with
    t the sum of the steps before it (every one drawn in 200 seeds, in about 40 % of the steps); the
    other kinds name none.  Catches a point computed from another time (t - 0.5 for t + 0.5), a wrong
    point never drawn, or the share off."""
    _, rows = table
    seen, named, steps = Counter(), 0, 0
    for seed in range(200):
        t = 0.0
        for op in make_case(MODEL, rows, seed, kind="order")["ops"]:
            if op[0] != "step":
                continue
            steps += 1
            if op[1] is not None:
                named += 1
                labels = {0.0: "0", -1.0: "-1", t + 0.5: "t+0.5", t - 1e-3: "t-1e-3", 1e300: "1e300"}
                label = "nan" if math.isnan(op[1]) else labels.get(op[1])
                assert label is not None, (seed, t, op)
                seen[label] += 1
            t += op[2]
    assert set(seen) == {"0", "-1", "t+0.5", "t-1e-3", "nan", "1e300"}, seen
    assert 0.3 < named / steps < 0.5, (named, steps)


def test_a_parameters_case_draws_hostile_values_or_values_near_the_start(table):
    """A "parameters" case's Real values are hostile (:data:`HOSTILE_REALS`) in about 60 % of the draws and
    otherwise within 50 % (plus 0.5 % absolute) of the parameter's start.  Catches the spread widened or
    the draw shifted away from the start (a mistyped bound), or the hostile share off."""
    _, rows = table
    start = {row[0]: row[4] for row in rows if row[2] == "parameter" and row[1] == "Real"}
    hostile = near = 0
    for seed in range(300):
        for name, value in make_case(MODEL, rows, seed, kind="parameters")["parameters"]:
            if name not in start:
                continue
            if any(value == h or (math.isnan(value) and math.isnan(h)) for h in HOSTILE_REALS):
                hostile += 1
                continue
            near += 1
            base = start[name]
            assert abs(value - base) <= 0.5 * abs(base) + 0.005 * (abs(base) or 1.0) + 1e-15, (name, value, base)
    assert 0.5 < hostile / (hostile + near) < 0.7, (hostile, near)


def _is_hostile(value) -> bool:
    return any(value == h or (math.isnan(value) and math.isnan(h)) for h in HOSTILE_REALS)


def test_an_inputs_case_draws_hostile_inputs_in_a_fifth_of_its_sets_and_sane_ones_otherwise(table):
    """An "inputs" case sets every Real input before every step: a hostile value
    (:data:`HOSTILE_REALS`) with probability 0.2 (make_case's docstring), otherwise within 2 %
    (and 2e-4 absolute) of its sane value.  Catches the hostile share off (0.4, or none), the
    other values drawn wider than 2 %, or away from the sane value."""
    _, rows = table
    start = {row[0]: row[4] for row in rows if row[2] == "input" and row[1] == "Real"}
    hostile = sane = 0
    for seed in range(300):
        for op in make_case(MODEL, rows, seed, kind="inputs")["ops"]:
            if op[0] != "set" or op[1] not in start:
                continue
            if _is_hostile(op[2]):
                hostile += 1
                continue
            sane += 1
            base = start[op[1]]
            assert abs(op[2] - base) <= 0.02 * abs(base) + 2e-4 * (abs(base) or 1.0) + 1e-15, op
    assert 0.16 < hostile / (hostile + sane) < 0.24, (hostile, sane)


def test_a_sets_case_writes_hostile_outputs_half_the_time_and_hostile_parameters_three_times_in_ten(table):
    """A "sets" case's extra writes of a Real output are hostile with probability 0.5, of a Real
    parameter 0.3 (make_case's docstring).  Catches either share off or the two swapped."""
    _, rows = table
    kind = {row[0]: (row[1], row[2]) for row in rows}
    counts = {"output": [0, 0], "parameter": [0, 0]}
    for seed in range(600):
        for op in make_case(MODEL, rows, seed, kind="sets")["ops"]:
            if op[0] == "set" and kind[op[1]] in (("Real", "output"), ("Real", "parameter")):
                counts[kind[op[1]][1]][_is_hostile(op[2])] += 1
    for causality, share in (("output", 0.5), ("parameter", 0.3)):
        sane, hostile = counts[causality]
        assert abs(hostile / (hostile + sane) - share) < 0.08, (causality, counts)


def test_a_case_takes_one_to_five_steps_and_only_order_cases_call_out_of_order(table):
    """Every kind steps 1 to 5 times (each count drawn in 300 seeds); only an "order" case adds a
    doStep before initialisation (in some cases, not all) and a terminate, get_state or set_state
    after a step; only a "lifecycle" case may instantiate with a wrong GUID (some, not all);
    logging is on in some cases and off in others.  Catches a step count off by one, the
    out-of-order calls leaking into other kinds or never drawn, and a share fixed at 0 or 1."""
    _, rows = table
    for kind in KINDS:
        counts, before_init, extra, guids, logging = Counter(), 0, Counter(), Counter(), Counter()
        for seed in range(300):
            case = make_case(MODEL, rows, seed, kind=kind, wrapper=True, models=(MODEL,))
            ops = case["ops"]
            counts[sum(op[0] == "step" for op in ops)] += 1
            before_init += ops[0][0] == "step_before_init"
            extra.update(op[0] for op in ops if op[0] in ("terminate", "get_state", "set_state"))
            guids[case["guid"]] += 1
            logging[case["logging"]] += 1
        assert set(counts) == {1, 2, 3, 4, 5}, (kind, counts)
        assert set(logging) == {True, False}, kind
        if kind == "order":
            assert 0 < before_init < 300 and set(extra) == {"terminate", "get_state", "set_state"}, (before_init, extra)
        else:
            assert before_init == 0 and (not extra or kind == "lifecycle"), (kind, extra)
        assert set(guids) == ({"own", "wrong"} if kind == "lifecycle" else {"own"}), (kind, guids)


def test_a_sets_case_raw_references_are_unsigned_32_bit_and_reach_both_ends_of_the_range(table):
    """fmi2ValueReference is an ``unsigned int`` (FMI 2.0 section 2.1.2): each raw reference a
    "sets" case writes fits 32 bits unsigned, both ends (0 and 2**32 - 1, the largest an FMU can
    be handed) are drawn, and its type is one of the four FMI types.  Catches a reference one past
    the range (ctypes would wrap it to 0 silently) or an end never drawn."""
    _, rows = table
    refs, types = Counter(), set()
    for seed in range(300):
        for op in make_case(MODEL, rows, seed, kind="sets")["ops"]:
            if op[0] == "set_vr":
                refs[op[2]] += 1
                types.add(op[1])
    assert all(isinstance(vr, int) and 0 <= vr <= 2 ** 32 - 1 for vr in refs), refs
    assert refs[0] > 0 and refs[2 ** 32 - 1] > 0, refs
    assert types == {"Real", "Integer", "Boolean", "String"}


def _ends(rows, kind, what, seeds=300):
    """Counter of where the ops ``what(op)`` picks land in the ops of ``kind`` cases: "first"
    (before anything, inputs included), "last" (after the last get), "inside"."""
    where = Counter()
    for seed in range(seeds):
        ops = make_case(MODEL, rows, seed, kind=kind, wrapper=True, models=(MODEL, "Derivator"))["ops"]
        for k, op in enumerate(ops):
            if what(op):
                where["first" if k == 0 else "last" if k == len(ops) - 1 else "inside"] += 1
    return where


def test_the_extra_calls_of_a_case_land_anywhere_in_its_calls_the_very_first_and_the_very_last_included(table):
    """Seed 4101's survivor [146] (cases.py:204, a parameter's write inserted from index 1:
    never before the inputs' first sets).  A "sets" case's writes of an output, of a parameter
    and of a raw reference, and a "lifecycle" case's out-of-order calls, are each put at a
    position drawn over all the case's calls: each is drawn first (right after initialisation,
    before any input is set or step taken), last (after the final get) and in between.  A
    state case's bytes come after the first call and
    may come last.  Catches a lower or upper end of a draw off by one (the FMU then never
    meets that write at that point of its life)."""
    _, rows = table
    causality = {row[0]: row[2] for row in rows}
    for what, kind, picks in (
            ("output", "sets", lambda op: op[0] == "set" and causality[op[1]] == "output"),
            ("parameter", "sets", lambda op: op[0] == "set" and causality[op[1]] == "parameter"),
            ("raw reference", "sets", lambda op: op[0] == "set_vr"),
            ("lifecycle call", "lifecycle", lambda op: op[0] in ("exit_init_again", "enter_init_again",
                                                                  "setup_again"))):
        where = _ends(rows, kind, picks)
        assert set(where) == {"first", "last", "inside"}, (what, where)
    state = _ends(rows, "state", lambda op: op[0] == "state_bytes")
    assert set(state) == {"last", "inside"} and sum(state.values()) == 300, state
