"""The library's differential tests as test vectors on every target.

toolchain/vectors.py generates the inputs and the NumPy reference's
expected outputs; csrc/vectors/run_vectors.c runs the library on them.
The same vectors run on the host, on the bare ARMv4T core
(``qemu-arm -cpu ti925t``: the run itself proves every executed
instruction is ARMv4T; a v5 instruction would raise SIGILL) and on ARMv4T
Linux under ``qemu-arm``, each in the double and the float build.
Tolerances: toolchain.vectors.tolerance (derived from the unit roundoff
of each build and the number of roundings behind each output).
"""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import ROOT, require_target

from toolchain import vectors as V

pytestmark = pytest.mark.system  # builds and runs the test-vector programs on every target


@pytest.fixture(scope="module")
def vector_file(tmp_path_factory: pytest.TempPathFactory) -> tuple[list[V.Case], Path]:
    cases = V.generate()
    path = V.write(cases, tmp_path_factory.mktemp("vectors") / "vectors.txt")
    return cases, path


@pytest.mark.parametrize("precision", ["f64", "f32"])
@pytest.mark.parametrize("target", ["host", "armv4t-bare", "armv4t"])
def test_vectors_on_target(target: str, precision: str, vector_file, build_root: Path) -> None:
    cases, path = vector_file
    t = require_target(target)
    exe = t.build_program([V.RUNNER_SRC], build_root / "vectors" / target / precision / "run_vectors",
                          defines=["ATT_REAL_F32"] if precision == "f32" else [])
    proc = t.run([exe, path], timeout=120, check=False)
    out = proc.stdout.decode(errors="replace")
    assert proc.returncode == 0, out[-2000:] + proc.stderr.decode(errors="replace")
    results, summary = V.parse(out)
    size = 4 if precision == "f32" else 8
    assert summary == f"vectors: {len(cases)} cases, {size} bytes of att_real", summary
    bad = V.compare(cases, results, precision)
    assert not bad, "\n".join(bad)


def test_vectors_cover_every_public_function() -> None:
    """Every array function of quat.h, the integrator methods and rk4, the link machines, the
    denoiser, the sensor converter and the aiding solvers have vectors."""
    header = (ROOT / "csrc" / "include" / "attitude" / "quat.h").read_text()
    import re

    public = set(re.findall(r"\batt_(\w+)_n\(", header))
    funcs = {c.func for c in V.generate(n=4)}
    assert public <= funcs | {"quat_mul"}, public - funcs
    assert {"quat_mul", "quat_conj", "integ", "rk4", "link_checksum", "link_rx", "link_tx"} <= funcs
    assert {"wden_dwt", "wden_idwt", "wden_stream", "sensor"} <= funcs
    assert {"align", "triad", "gn", "align_window", "magcal", "magcal2d", "magcal_apply"} <= funcs
    methods = {c.params[0] for c in V.generate(n=4) if c.func == "integ"}
    assert set(V.INCREMENT_METHODS) <= methods


def test_vectors_detect_a_wrong_result(vector_file) -> None:
    """The comparison is not vacuous: a perturbed result is reported."""
    cases, _ = vector_file
    c = next(c for c in cases if c.func == "quat_to_dcm" and c.status_ok)
    assert c.expected is not None
    vals = c.expected.copy()
    vals[3, 4] += 1e-9  # above the f64 tolerance for quat_to_dcm
    res = {c.id: V.Result(0, -1, vals)}
    assert V.compare([c], res, "f64")
    res = {c.id: V.Result(0, -1, c.expected.copy())}
    assert V.compare([c], res, "f64") == []
