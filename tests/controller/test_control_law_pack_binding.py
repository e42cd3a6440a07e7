"""``controller.law.pack``'s words read back against ``kernels/src/law.h``, and
``controller.law.binding`` remade whenever any one of its four buffers is replaced.

``law.h`` is the independent source: its ``#define`` codes and the comments of
``pc_law_params`` (``kp, kv: lam^2, 2 lam``; ``adaptive: 1 ... 0 ...``) say what each word holds.
"""

import re
from pathlib import Path

import numpy as np
import pytest

from controller import law
from controller.kinematics import Kinematics
from plant import get_preset

BENCH = get_preset("bench")
LAW_H = Path(law.__file__).resolve().parents[1] / "kernels" / "src" / "law.h"


def _defines():
    """``#define PC_LAW_<NAME> <number>`` of law.h as {name: float}."""
    text = LAW_H.read_text()
    return {m[1]: float(m[2]) for m in re.finditer(r"#define PC_LAW_(\w+) ([-+0-9.eE]+)\s", text)}


def test_the_mode_codes_are_law_hs_defines():
    d = _defines()
    assert law.SPACES == {"q": d["SPACE_Q"], "x": d["SPACE_X"]}
    assert law.MODELS == {None: d["MODEL_PD"], "tabulated": d["MODEL_TABULATED"], "exact": d["MODEL_EXACT"]}
    assert law.LAWS == {"unified": d["UNIFIED"], "seed001": d["SEED"]}


@pytest.mark.parametrize("gamma", [None, (3.0, 4.0)])
def test_pack_writes_each_parameter_word_as_law_h_documents_it(gamma):
    kin = Kinematics(BENCH)
    lam, phi, m_star, kt, predict = 7.5, 0.02, 0.125, (0.056, 0.0567), (2, 1)
    buf = law.pack(kin, 0.003, "x", "exact", lam, phi, gamma, m_star, kt, law="seed001", predict=predict)
    assert buf.size == law.STATE_SIZE + law.PARAMS_SIZE
    # the state (every word a run changes) starts at zero
    assert np.all(buf[:law.STATE_SIZE] == 0.0)
    w = {name: buf[s].tolist() for name, s in law.BUF.items() if s.start >= law.STATE_SIZE}
    assert w["geometry"] == [BENCH.l0, BENCH.chain1.l1, BENCH.chain1.l2, BENCH.chain2.l1, BENCH.chain2.l2]
    assert w["band"] == [0.003]
    assert (w["space"], w["model"], w["law"]) == ([1.0], [2.0], [1.0])
    # kp = lam^2, kv = 2 lam (7.29-7.30), lam, phi exactly
    assert (w["kp"], w["kv"], w["lam"], w["phi"]) == ([lam * lam], [lam + lam], [lam], [phi])
    # adaptive: 1 with the adaptive gain (6.66), 0 with the constant k
    assert w["adaptive"] == ([0.0] if gamma is None else [1.0])
    assert w["gamma"] == ([0.0, 0.0] if gamma is None else list(gamma))
    assert (w["m_star"], w["kt"], w["predict"]) == ([m_star], list(kt), [2.0, 1.0])


class _Owner:
    """Something to own a binding (weak-referenceable)."""


def _buffers():
    return (law.pack(Kinematics(BENCH), 0.003, "q", None, 5.0, 0.01, None, 0.1, (0.05, 0.05)),
            np.zeros(law.SCRATCH_SIZE), np.zeros(law.TERMS_SIZE), None)


def test_a_binding_is_kept_while_its_buffers_are_the_same_objects():
    owner = _Owner()
    arrays = _buffers()
    assert law.binding(owner, *arrays) is law.binding(owner, *arrays)


@pytest.mark.parametrize("which", range(3))
def test_a_binding_is_remade_when_any_one_buffer_is_replaced(which):
    owner = _Owner()
    arrays = list(_buffers())
    first = law.binding(owner, *arrays)
    arrays[which] = arrays[which].copy()    # the other three stay the very same objects
    second = law.binding(owner, *arrays)
    assert second is not first
    assert all(a is b for a, b in zip(second.arrays, arrays))


def test_a_binding_is_remade_when_the_table_is_replaced():
    owner = _Owner()
    buf, scratch, terms, _ = _buffers()
    table = np.zeros(2 * 2 * 7)
    first = law.binding(owner, buf, scratch, terms, table)
    second = law.binding(owner, buf, scratch, terms, table.copy())
    assert second is not first and second.arrays[3] is not table
