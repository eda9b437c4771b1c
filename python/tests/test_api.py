"""The Python API (PRODUCT.md section 6) against the command line and analytic facts.

Run by CTest (python_api): PYTHONPATH=build/python /usr/bin/python3 -m pytest python/tests
LAMINA_SOURCE (the source tree) and LAMINA_TEST_OUTPUT (a scratch folder) come from CTest."""
import copy
import json
import os
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest

import lamina

SOURCE = Path(os.environ.get("LAMINA_SOURCE", Path(__file__).resolve().parents[2]))
OUTPUT = Path(os.environ.get("LAMINA_TEST_OUTPUT", "/tmp/lamina_python_tests"))
PLATE = SOURCE / "examples" / "efg_clamped_plate.yaml"        # R1a quarter plate, uz(10,10,0.5) = -1.03190
CANTILEVER = SOURCE / "examples" / "mpfem_cantilever.yaml"    # Timoshenko cantilever, exact tip 0.0089


def small_pd_bar(levels=4):
    """A PD bar pulled quasi-statically in `levels` load steps (several output points, fast)."""
    return {
        "title": "PD bar in tension, quasi-static",
        "method": "pd",
        "materials": [{"name": "steel", "model": "linear_elastic", "E": 200.0e3, "nu": 0.25}],
        "geometry": {"type": "box", "min": [0, 0, 0], "max": [20, 4, 4]},
        "discretization": {"spacing": [1.0, 1.0, 1.0], "horizon_factor": 3.015},
        "boundary": [{"select": {"where": "x < 1.0"}, "fix": ["x", "y", "z"]}],
        "loads": [{"select": {"where": "x > 19.0"}, "force": [400.0, 0, 0]}],
        "pd": {"analysis": "quasi_static", "quasi_static": {"increments": levels}},
        "probes": [{"name": "u_end", "field": "displacement", "component": "x", "at": [19.5, 2, 2]}],
        "output": {"vtu": False},
    }


def test_load_reads_the_case_as_the_reader_does():
    case = lamina.load(PLATE)
    assert isinstance(case, dict) and case.source == str(PLATE)
    assert case["method"] == "efg"
    assert case["materials"][0]["E"] == pytest.approx(1.0e4) and isinstance(case["materials"][0]["E"], float)
    assert case["discretization"]["nodes"] == [11, 11, 3]
    assert case["output"]["vtu"] is True
    # the text run() writes reads back to the same dict
    text = lamina.dumps(case)
    path = OUTPUT / "roundtrip.yaml"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    assert dict(lamina.load(path)) == dict(case)
    # text that would read back as something else, or is not plain YAML, is quoted
    tricky = {"a": "1e4", "b": "true", "c": "{x", "d": "k: v", "e": "", "f": "null", "g": [1, 2.5, "3"], "h": None}
    path.write_text(lamina.dumps(tricky))
    assert dict(lamina.load(path)) == tricky


def test_case_from_a_dict_equals_the_command_line():
    case = lamina.load(PLATE)
    result = lamina.run(case, threads=1, output=OUTPUT / "plate_dict")
    assert result.status == "ok"
    # R1a reference (seed 004 Table 3-x, validation/efg_clamped_plate): within 2 % on this coarse grid
    assert result.probes["w_centre"] == pytest.approx(-1.03190, rel=0.02)
    # the same case through the command line gives the same numbers
    cli = OUTPUT / "plate_cli"
    binary = os.environ.get("LAMINA", str(SOURCE / "build" / "lamina"))
    subprocess.run([binary, "run", str(PLATE), "-o", str(cli), "--quiet", "--threads", "1"], check=True)
    summary = json.loads((cli / "summary.json").read_text())
    for name, value in summary["probes"].items():
        assert result.probes[name] == pytest.approx(value, rel=1e-12, abs=1e-300), name
    # history as a structured array with the probe columns
    assert result.history.dtype.names[:3] == ("step", "time", "load_factor")
    assert "w_centre" in result.history.dtype.names
    assert result.history["w_centre"][-1] == result.probes["w_centre"]


def test_a_sweep_of_three_runs_is_linear_in_the_compliance():
    base = lamina.load(PLATE)
    base["output"]["vtu"] = False
    w = {}
    for E in (1.0e4, 2.0e4, 4.0e4):
        case = copy.deepcopy(base)
        case["materials"][0]["E"] = E
        w[E] = lamina.run(case, threads=1, output=OUTPUT / f"sweep_E{E:g}").probes["w_centre"]
    # linear elasticity with fixed nu: w E is independent of E
    for E in (2.0e4, 4.0e4):
        assert w[E] * E == pytest.approx(w[1.0e4] * 1.0e4, rel=1e-9)


def test_a_bad_value_raises_input_error_with_its_line():
    case = lamina.load(PLATE)
    case["materials"][0]["E"] = "soft"
    out = OUTPUT / "bad_value"
    with pytest.raises(lamina.InputError) as error:
        lamina.run(case, output=out)
    message = str(error.value)
    match = re.search(r"bad_value\.yaml:(\d+):(\d+): materials\.0\.E", message)
    assert match, message
    line = (out.parent / "bad_value.yaml").read_text().splitlines()[int(match.group(1)) - 1]
    assert "soft" in line
    assert not out.exists()  # nothing ran, no result set


def test_an_unknown_key_raises_input_error_naming_it():
    case = lamina.load(PLATE)
    case["efg"]["basiss"] = "linear"
    with pytest.raises(lamina.InputError, match=r"efg\.basiss"):
        lamina.run(case, output=OUTPUT / "unknown_key")
    with pytest.raises(lamina.InputError, match=r"cannot be opened|no such|readable"):
        lamina.load(OUTPUT / "no_such_case.yaml")


def test_fields_equal_the_vtu():
    vtk = pytest.importorskip("vtk")
    from vtk.util.numpy_support import vtk_to_numpy

    result = lamina.run(PLATE, threads=1, output=OUTPUT / "plate_fields")
    u = result.fields("displacement")
    assert u.shape == (result.points.shape[0], 3)
    frames = sorted((result.output_directory).glob("*.vtu"))
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(str(frames[-1]))
    reader.Update()
    grid = reader.GetOutput()
    assert np.array_equal(vtk_to_numpy(grid.GetPoints().GetData()), result.points)
    for name in result.field_names:
        array = vtk_to_numpy(grid.GetPointData().GetArray(name))
        assert np.array_equal(array.reshape(result.fields(name).shape), result.fields(name)), name
    with pytest.raises(KeyError, match="no field"):
        result.fields("no_such_field")


def test_on_output_sees_every_point_and_can_stop_the_run():
    seen = []
    full = lamina.run(small_pd_bar(), threads=1, output=OUTPUT / "pd_full",
                      on_output=lambda state: seen.append((state.load_factor, state.probes["u_end"])))
    assert full.status == "ok"
    assert len(seen) == len(full.history) >= 4
    assert [s[1] for s in seen] == list(full.history["u_end"])
    # bar of length 19 between the held layer and the probe, area 16: u = F L / (E A) within 2 %
    assert full.probes["u_end"] == pytest.approx(400.0 * 19.0 / (200.0e3 * 16.0), rel=0.02)
    stopped = lamina.run(small_pd_bar(), threads=1, output=OUTPUT / "pd_stopped",
                         on_output=lambda state: state.load_factor < 0.5)
    assert stopped.status == "stopped"
    assert 0 < len(stopped.history) < len(full.history)
    assert np.array_equal(stopped.history["u_end"], full.history["u_end"][: len(stopped.history)])
    summary = json.loads((OUTPUT / "pd_stopped" / "summary.json").read_text())
    assert summary["status"] == "stopped"


def test_relative_files_are_found_from_the_loaded_case():
    # a case that names a file relative to itself, loaded and run from another working directory
    folder = OUTPUT / "relative"
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "particles.csv").write_text("x,y,z\n" + "".join(f"{x},{y},0.5\n" for x in range(0, 49, 3) for y in (-6, -3, 0, 3, 6)))
    case = lamina.load(CANTILEVER)
    case["discretization"] = {"particles": {"file": "particles.csv"}}
    case["output"] = {"vtu": False}
    # a particle file has no named edge sets: the clamped and loaded ends by coordinates
    case["boundary"][0]["select"] = {"where": "x < 1e-9"}
    case["loads"][0]["select"] = {"where": "x > 48 - 1e-9"}
    case["probes"][2]["select"] = {"where": "x < 1e-9"}
    (folder / "cantilever_file.yaml").write_text(lamina.dumps(case))
    loaded = lamina.load(folder / "cantilever_file.yaml")
    cwd = os.getcwd()
    try:
        os.chdir("/")
        result = lamina.run(loaded, threads=1, output=OUTPUT / "relative_run")
    finally:
        os.chdir(cwd)
    assert result.probes["tip_deflection"] == pytest.approx(0.0089, rel=0.05)


def test_an_exception_in_on_output_reaches_the_caller():
    def fail(state):
        if state.load_factor > 0.3:
            raise ZeroDivisionError("stop here")
    out = OUTPUT / "pd_raised"
    with pytest.raises(ZeroDivisionError, match="stop here"):
        lamina.run(small_pd_bar(), threads=1, output=out, on_output=fail)
    assert not out.exists()
    assert not list(OUTPUT.glob("pd_raised.partial-*"))
