"""libcosim's OSP annotation (fmus/ssp/export.py ``libcosim_annotation``, ``libcosim_annotation_xml``),
no libcosim needed: the element and its text agree, the step written exactly (``repr``), the worker
threads written only when given; a step that is not a finite number > 0 and a thread count that is
not an integer >= 0 refused word for word, at their edges (issue 31: these ran only in the slow
file of libcosim's runs, which a mutant's tests reach last)."""
from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import pytest

from fmus.ssp.export import NS, OSP_ANNOTATION, OSP_NS, libcosim_annotation, libcosim_annotation_xml


def _algorithm(text: str) -> ET.Element:
    root = ET.fromstring(f'<r xmlns:ssc="{NS["ssc"]}" xmlns:osp="{OSP_NS}">{text}</r>')
    annotation = root.find("ssc:Annotation", NS)
    assert annotation.get("type") == OSP_ANNOTATION == "com.opensimulationplatform"
    return annotation.find(f"{{{OSP_NS}}}Algorithm/{{{OSP_NS}}}FixedStepAlgorithm")


@pytest.mark.parametrize("step, threads", [(1e-3, None), (2.5e-4, 0), (5e-324, 3), (0.1 + 0.2, 1)])
def test_the_text_and_the_element_carry_the_step_exactly_and_the_threads_when_given(step, threads):
    """Catches an OSP annotation libcosim does not read (another type, namespace or attribute
    name), a step rounded on the way (0.30000000000000004 written as 0.3), the smallest positive
    step refused, the threads written when not given, and the element and the text apart."""
    expected = {"baseStepSize": repr(step), **({} if threads is None else {"numWorkerThreads": str(threads)})}
    assert _algorithm(libcosim_annotation_xml(step, threads)).attrib == expected
    element = libcosim_annotation(step, threads)
    assert element.tag == f"{{{NS['ssc']}}}Annotation" and element.get("type") == OSP_ANNOTATION
    assert element.find(f"{{{OSP_NS}}}Algorithm/{{{OSP_NS}}}FixedStepAlgorithm").attrib == expected
    assert float(expected["baseStepSize"]) == step


@pytest.mark.parametrize("step", [0.0, -0.0, -1e-3, -5e-324, math.nan, math.inf, -math.inf])
def test_a_step_that_is_not_a_finite_number_above_zero_is_refused_by_name(step):
    """Catches 0 taken (``>=`` for ``>``), a negative, NaN or infinite step written."""
    for write in (libcosim_annotation, libcosim_annotation_xml):
        with pytest.raises(ValueError) as refused:
            write(step)
        assert str(refused.value) == f"step = {float(step)!r} must be a finite number > 0"


@pytest.mark.parametrize("threads", [-1, 1.5, True, False])
def test_worker_threads_that_are_not_an_integer_of_at_least_zero_are_refused_by_name(threads):
    """Catches -1 taken (the bound moved), a fraction or a bool taken as a count."""
    for write in (libcosim_annotation, libcosim_annotation_xml):
        with pytest.raises(ValueError) as refused:
            write(1e-3, threads)
        assert str(refused.value) == f"worker_threads = {threads!r} must be an integer >= 0"
