"""lamina from Python (PRODUCT.md section 6): load a case as a dict, change it, run it, read the results.

    import lamina
    case = lamina.load("examples/efg_clamped_plate.yaml")   # the case as a dict (lamina.Case)
    case["materials"][0]["E"] = 2.0e4
    result = lamina.run(case, threads=2)                     # a dict or a path
    result.probes["w_centre"]                                # float
    result.history                                           # numpy structured array
    result.fields("displacement")                            # numpy array (n x 3), last output point

The same C++ code as `lamina run` reads, checks and runs the case; its one-line messages
(file:line:column, key path, expected, found) arrive as lamina.InputError, a failed analysis
(exit 3 of the command line) as lamina.AnalysisError. A case given as a dict is written as YAML
beside its result folder (OUTDIR.yaml) first, so the lines of a message point into that file.
"""
from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Callable, Iterable, Optional, Union

import numpy as np

from . import _lamina

__all__ = ["Case", "Result", "OutputState", "InputError", "AnalysisError", "load", "dumps", "run"]


class InputError(ValueError):
    """A case that cannot be run: the command line's messages (exit 2), one problem per line."""


class AnalysisError(RuntimeError):
    """The analysis failed (exit 3: non-finite values, divergence, a singular system).

    `result` holds what was written up to the last good output point."""

    def __init__(self, message: str, result: "Result"):
        super().__init__(message)
        self.result = result


class Case(dict):
    """A case as a dict; `source` is the file it was loaded from (relative file names in the case,
    such as particle files or meshes, are found from that file's folder)."""

    source: Optional[str] = None


class OutputState:
    """What on_output(state) receives at each output point."""

    def __init__(self, step: int, time: float, load_factor: float, probes: dict):
        self.step, self.time, self.load_factor, self.probes = step, time, load_factor, probes

    def __repr__(self) -> str:
        return f"OutputState(step={self.step}, time={self.time:g}, load_factor={self.load_factor:g}, probes={self.probes})"


class Result:
    """The result of one run: probes, history and the last output point's fields."""

    def __init__(self, raw: dict):
        self.summary: dict = json.loads(raw["summary"])
        self.output_directory = Path(raw["output_directory"])
        self.status: str = self.summary.get("status", "")
        self.warnings: list = self.summary.get("warnings", [])
        self.probes: dict = {k: float(v) for k, v in self.summary.get("probes", {}).items()}
        columns = raw["history_columns"]
        dtype = [(name, np.int64 if name == "step" else np.float64) for name in columns]
        self.history = np.array([tuple(int(v) if k == 0 else v for k, v in enumerate(row)) for row in raw["history_rows"]],
                                dtype=dtype)
        self.points: Optional[np.ndarray] = raw.get("points")
        self._fields: dict = raw.get("fields", {})

    @property
    def field_names(self) -> list:
        return list(self._fields)

    def fields(self, name: str) -> np.ndarray:
        """A point field at the last output point: (n,) for a scalar, (n, components) otherwise."""
        if name not in self._fields:
            raise KeyError(f"no field '{name}' in this result (fields: {', '.join(self._fields) or 'none'})")
        return self._fields[name]

    def __repr__(self) -> str:
        return f"Result(status={self.status!r}, probes={self.probes}, output_directory='{self.output_directory}')"


def _input_error(message: str) -> InputError:
    return InputError(message.rstrip("\n"))


def load(path: Union[str, os.PathLike]) -> Case:
    """The case file at `path` as a dict (numbers, booleans and text read as the case reader reads them)."""
    try:
        case = Case(_lamina.load_yaml(os.fspath(path)) or {})
    except _lamina.InputErrorBase as e:
        raise _input_error(str(e)) from None
    case.source = os.path.abspath(os.fspath(path))
    return case


def dumps(case: dict) -> str:
    """The YAML text lamina.run writes for a dict case (the lines its messages refer to)."""
    try:
        return _lamina.dump_yaml(dict(case))
    except _lamina.InputErrorBase as e:
        raise _input_error(str(e)) from None


def run(case: Union[dict, str, os.PathLike], threads: int = 0, on_output: Optional[Callable[[OutputState], bool]] = None,
        output: Optional[Union[str, os.PathLike]] = None, overrides: Iterable[str] = (), quiet: bool = True) -> Result:
    """Run a case (a dict or a case file's path) as `lamina run` does and return its Result.

    threads: OpenMP threads (0: the default); output: the result folder (default out/<case name>);
    overrides: "key.path=value" strings as --set gives them; on_output(state) is called at each output
    point, and returning False ends the run there cleanly (status "stopped")."""
    case_directory = ""
    if isinstance(case, dict):
        source = getattr(case, "source", None)
        name = Path(source).stem if source else "case"
        out = Path(output) if output is not None else Path("out") / name
        case_directory = str(Path(source).parent) if source else os.getcwd()
        out.parent.mkdir(parents=True, exist_ok=True)
        path = out.parent / (out.name + ".yaml")
        path.write_text(dumps(case))
    else:
        path = Path(case)
        out = Path(output) if output is not None else Path("")
    callback = None
    if on_output is not None:
        def callback(step, time, load_factor, probes):
            answer = on_output(OutputState(step, time, load_factor, probes))
            return answer is None or bool(answer)
    raw = _lamina.run_case(str(path), str(out) if str(out) not in ("", ".") else "", int(threads), list(overrides),
                           case_directory, callback, bool(quiet))
    code, message = raw["exit_code"], raw["error"]
    if code == 2:
        raise _input_error(message)
    if code == 1:
        raise RuntimeError(f"lamina: internal error: {message}")
    if code >= 128:
        raise KeyboardInterrupt(message)
    result = Result(raw)
    if code == 3:
        raise AnalysisError(message, result)
    return result
