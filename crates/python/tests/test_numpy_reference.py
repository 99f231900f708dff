"""The numpy reference of the performance comparison (benches/reference/rv20e_numpy.py)
still does rvtol's job: run on the shipped scenario, its statistics agree with rvtol's
within Monte Carlo error (benches/reference/compare_rv20e.py: every figure within 4
combined standard errors). Fixed seeds, so the check is deterministic; it fails when the
scenario or the model moves and the reference does not follow.

RVTOL_CLI names the rvtol binary (default: target/release/rvtol of the repository)."""

import importlib.util
import json
import os
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[3]
CLI = os.environ.get("RVTOL_CLI", str(ROOT / "target" / "release" / "rvtol"))
REFERENCE = ROOT / "benches" / "reference"
SAMPLES = "200000"


def load_compare():
    spec = importlib.util.spec_from_file_location("compare_rv20e", REFERENCE / "compare_rv20e.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_numpy_reference_agrees_with_rvtol(tmp_path):
    numpy_json, rvtol_json = tmp_path / "numpy.json", tmp_path / "rvtol.json"
    done = subprocess.run(
        [sys.executable, str(REFERENCE / "rv20e_numpy.py"), "--samples", SAMPLES, "--seed", "1",
         "--json", str(numpy_json)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    done = subprocess.run(
        [CLI, "run", str(ROOT / "scenarios" / "rv20e-hysteresis.json"), "--samples", SAMPLES,
         "--seed", "2", "--quiet", "--json", str(rvtol_json)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    numpy, rvtol = json.loads(numpy_json.read_text()), json.loads(rvtol_json.read_text())
    rows = list(load_compare().rows(numpy, rvtol))
    # Every output and indicator of the model is compared (8 continuous outputs, the
    # hysteresis out-of-spec fraction, 2 indicators).
    assert len({figure.rsplit(" ", 1)[0] for figure, *_ in rows}) >= 11
    for figure, a, b, se in rows:
        if se == 0.0:
            assert a == b, figure
        else:
            assert abs(a - b) <= 4.0 * se, f"{figure}: numpy {a} rvtol {b} SE {se}"
