"""scenarios/batch/worker_path.py, the sweeps' worker preload, on folders made here (the sweep
that needs it runs on dask and is of the slow kind): which entries are an extracted FMU's
resources folder, and what ``dask_setup`` leaves on ``sys.path`` (issue 31: each condition of a
test on its own)."""
from __future__ import annotations

import sys

from scenarios.batch import worker_path


def _fmu(root, name, description=True, folder="resources"):
    """An extracted FMU's folder: ``folder`` inside it, modelDescription.xml beside it or not."""
    unzipped = root / name
    (unzipped / folder).mkdir(parents=True)
    if description:
        (unzipped / "modelDescription.xml").write_text("<fmiModelDescription/>")
    return unzipped / folder


def test_only_a_resources_folder_beside_a_model_description_is_an_fmus(tmp_path):
    """Catches the test made on another path than the entry's (its parent, the working
    folder), the name or the description dropped, or the description taken as a folder."""
    assert worker_path.is_fmu_resources(str(_fmu(tmp_path, "a")))
    assert not worker_path.is_fmu_resources(str(_fmu(tmp_path, "b", description=False)))
    assert not worker_path.is_fmu_resources(str(_fmu(tmp_path, "c", folder="sources")))
    assert not worker_path.is_fmu_resources(str(tmp_path / "a"))               # the FMU's folder itself
    (tmp_path / "d" / "modelDescription.xml").mkdir(parents=True)               # a folder of that name
    (tmp_path / "d" / "resources").mkdir()
    assert not worker_path.is_fmu_resources(str(tmp_path / "d" / "resources"))
    assert not worker_path.is_fmu_resources("")


def test_the_preload_drops_exactly_the_fmus_resources_from_the_path_in_order(tmp_path, monkeypatch):
    """Catches the hook dropping other entries (a folder named resources without a description,
    the FMU's own folder), keeping one, or changing the order of the rest."""
    fmu = str(_fmu(tmp_path, "a"))
    other = str(_fmu(tmp_path, "b", description=False))
    path = [str(tmp_path), fmu, other, str(tmp_path / "a"), fmu, sys.path[0]]
    monkeypatch.setattr(sys, "path", list(path))
    worker_path.dask_setup()
    assert sys.path == [str(tmp_path), other, str(tmp_path / "a"), path[-1]]
