"""The filters' settings helper (attitude_c/_settings.py): names and kinds read from the
library's settings structs, each keyword checked by name, the domain error naming the
setting that is outside it. Truth: the headers' text (struct fields) and the C checks'
documented domains."""

from __future__ import annotations

import re
import subprocess
import sys

import numpy as np
import pytest
from conftest import ROOT

from attitude_c import ahrs_filter, thesis_ekf
from attitude_c.errors import InvalidArgument, InvalidType

INCLUDE = ROOT / "csrc" / "include" / "attitude"


def _struct_fields(header: str, struct: str) -> list[tuple[str, str]]:
    """(type, name) of each field of ``typedef struct {...} struct;`` in the header's text."""
    text = re.sub(r"/\*.*?\*/", " ", (INCLUDE / header).read_text(), flags=re.DOTALL)
    body = re.search(r"typedef struct \{([^}]*)\}\s*" + struct + ";", text)
    assert body is not None, struct
    return re.findall(r"(\w+)\s+(\w+)\s*;", body.group(1))


def test_names_are_the_structs_fields() -> None:
    ahrs_fields = _struct_fields("ahrs.h", "att_ahrs_settings")
    assert list(ahrs_filter.SETTINGS) == [n for t, n in ahrs_fields if t == "att_real"]
    assert list(ahrs_filter.default_settings()) == [n for _, n in ahrs_fields]  # method included
    tekf_fields = _struct_fields("ahrs_thesis.h", "att_tekf_settings")
    assert list(thesis_ekf.SETTINGS) == [n for t, n in tekf_fields if t == "att_real"]
    assert list(thesis_ekf.default_settings()) == [*thesis_ekf.SETTINGS, "gn_max_iter"]


def test_settings_round_trip() -> None:
    d = ahrs_filter.default_settings()
    assert ahrs_filter.Ahrs(rate=100.0, **d).settings == d
    f = ahrs_filter.Ahrs(rate=100.0, method="rv2", acc_tau=np.float32(1.5), rest_time=0)
    assert (f.settings["method"], f.settings["acc_tau"], f.settings["rest_time"]) == ("rv2", 1.5, 0.0)


def _gam(n: int = 5) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return np.zeros((n, 3)), np.tile([0.0, 0.0, 9.81], (n, 1)), np.tile([0.0, 20.0, -40.0], (n, 1))


def test_each_setting_is_checked_by_name() -> None:
    with pytest.raises(InvalidArgument, match=r"unknown filter setting 'acc_tauu' \(known: method, gravity, "):
        ahrs_filter.Ahrs(acc_tauu=1.0)
    with pytest.raises(InvalidType, match="acc_tau must be a real number, got str"):
        ahrs_filter.Ahrs(acc_tau="2")
    with pytest.raises(InvalidType, match="acc_tau must be a real number, got bool"):
        ahrs_filter.Ahrs(acc_tau=True)
    with pytest.raises(InvalidArgument, match="acc_tau must be finite"):
        ahrs_filter.Ahrs(acc_tau=np.inf)
    with pytest.raises(InvalidType, match="method must be a method name"):
        ahrs_filter.Ahrs(method=3)
    with pytest.raises(InvalidArgument, match="method must be one of"):
        ahrs_filter.Ahrs(method="rv9")
    g, a, m = _gam()
    with pytest.raises(InvalidType, match="gn_max_iter must be an integer, got float"):
        thesis_ekf.run(g, a, m, rate=100.0, gn_max_iter=20.0)
    with pytest.raises(InvalidArgument, match=r"gn_max_iter must be in 0\.\.4294967295 \(C unsigned int\), got -1"):
        thesis_ekf.run(g, a, m, rate=100.0, gn_max_iter=-1)


def test_the_domain_error_names_the_bad_setting() -> None:
    # acc_noise > 0 (ahrs.h); gyr_noise 0.02 alone is inside: only acc_noise is named
    with pytest.raises(InvalidArgument, match=r"settings: acc_noise=-1.0 outside its domain \(ahrs.h") as e:
        ahrs_filter.Ahrs(gyr_noise=0.02, acc_noise=-1.0)
    assert "gyr_noise" not in str(e.value)
    g, a, m = _gam()
    # gn.max_iter 1..1000 (ahrs_thesis.h, aiding.h)
    with pytest.raises(InvalidArgument, match=r"settings: gn_max_iter=1001 outside its domain"):
        thesis_ekf.run(g, a, m, rate=100.0, gn_max_iter=1001)
    with pytest.raises(InvalidArgument, match=r"meas_noise=0.0, declination=4.0 outside their domains"):
        thesis_ekf.run(g, a, m, rate=100.0, meas_noise=0.0, declination=4.0, gyr_noise=0.02)
    assert thesis_ekf.run(g, a, m, rate=100.0, gn_max_iter=1000).q.shape == (5, 4)


@pytest.mark.system
def test_importing_the_filters_loads_no_extension() -> None:
    code = ("import sys, attitude_c.ahrs_filter, attitude_c.thesis_ekf\n"
            "assert not [m for m in sys.modules if m.startswith('attitude_c._att_')], sys.modules")
    subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT)


def test_the_library_names_each_field_outside_its_domain() -> None:
    """att_ahrs_check_settings_field covers every field of att_ahrs_settings (a NaN is
    outside every domain) and names it as the struct spells it, the first in the struct's
    order when several are out."""
    from attitude_c._lib import ffi_lib

    for precision in ("f64", "f32"):
        ffi, lib = ffi_lib(precision)
        name = ffi.new("const char **")
        for field in ahrs_filter.SETTINGS:
            s = ffi.new("att_ahrs_settings *")
            lib.att_ahrs_default_settings(s)
            setattr(s, field, float("nan"))
            assert lib.att_ahrs_check_settings_field(s, name) == lib.ATT_E_AHRS_SETTINGS
            assert ffi.string(name[0]).decode() == field
        lib.att_ahrs_default_settings(s)
        s.method = lib.ATT_METHOD_RK4
        assert lib.att_ahrs_check_settings_field(s, name) == lib.ATT_E_AHRS_SETTINGS
        assert ffi.string(name[0]) == b"method"
        lib.att_ahrs_default_settings(s)
        assert lib.att_ahrs_check_settings_field(s, name) == 0 and name[0] == ffi.NULL
    # two outside: the message names the first in the struct's order (acc_noise before mag_delay)
    with pytest.raises(InvalidArgument, match=r"settings: acc_noise=-1.0 outside its domain \(ahrs.h") as e:
        ahrs_filter.Ahrs(mag_delay=0.06, acc_noise=-1.0)
    assert "mag_delay=" not in str(e.value)
