"""One source for names and codes (attitude_c.names): the table the Python
package reads from the compiled library agrees with the headers' enums, value
for value; every status code has a meaning; method names, their numbers and
their samples per update are the library's; no Python module types a status
code again."""

from __future__ import annotations

import ast
import re

from conftest import ROOT

import attitude_c
from attitude_c import core, fixedpoint, names, reference
from attitude_c.link.protocol import Result

HEADERS = sorted((ROOT / "csrc" / "include" / "attitude").glob("*.h")) + [
    ROOT / "csrc" / "host" / "tlc2543_model.h", ROOT / "csrc" / "host" / "ad7927_model.h",
    ROOT / "csrc" / "host" / "link_sim.h"]


def _header_enums() -> dict[str, int]:
    """Every enum constant of the headers (the C compiler's rules: a constant without a
    value is the previous one plus 1), read from the text."""
    out: dict[str, int] = {}
    for h in HEADERS:
        text = re.sub(r"/\*.*?\*/", " ", h.read_text(), flags=re.DOTALL)
        text = re.sub(r"//[^\n]*", " ", text)
        for body in re.findall(r"\benum\b[^{;]*\{([^}]*)\}", text):
            nxt = 0
            for item in (x.strip() for x in body.split(",")):
                if not item:
                    continue
                name, _, expr = (p.strip() for p in item.partition("="))
                assert re.fullmatch(r"[A-Za-z_]\w*", name), (h.name, item)
                if expr:
                    expr = re.sub(r"(?<=[0-9a-fA-F])[uUlL]+\b", "", expr)
                    nxt = int(eval(expr, {"__builtins__": {}}, dict(out)))  # literals and earlier names
                out[name] = nxt
                nxt += 1
    return out


def test_the_table_is_the_headers() -> None:
    enums = {k: v for k, v in _header_enums().items() if k.startswith(names.PREFIXES)}
    assert len(enums) > 150
    table = dict(names.C)
    assert table == enums, ({k: (table.get(k), v) for k, v in enums.items() if table.get(k) != v},
                            sorted(set(table) - set(enums)))


def test_every_status_code_has_one_name_and_a_meaning() -> None:
    from attitude_c import denoise, tlc2543
    from attitude_c._lib import ffi_lib
    from attitude_c.ad7927 import _capi as ad7927_capi

    codes = {k: v for k, v in names.C.items() if v < 0 and "_E_" in k}
    assert len(set(codes.values())) == len(codes)  # ranges per module (common.h): no value twice
    assert all(names.status_name(v) == k for k, v in codes.items())
    meanings = {**names.STATUS, **tlc2543._STATUS, **ad7927_capi.STATUS,
                **denoise._status_table(ffi_lib("f64")[1])}
    assert set(meanings) <= set(codes), set(meanings) - set(codes)  # no stale name
    assert set(codes) <= set(meanings), set(codes) - set(meanings)  # no code without a meaning


def test_raise_for_status_names_the_code() -> None:
    import pytest

    from attitude_c.errors import InvalidArgument, NonFiniteError, RangeError
    from attitude_c.names import raise_for_status

    with pytest.raises(NonFiniteError, match=r"x: non-finite .* at sample 4 \(status -3, ATT_E_NONFINITE\)") as e:
        raise_for_status(names.C["ATT_E_NONFINITE"], "x", index=4)
    assert e.value.index == 4
    with pytest.raises(RangeError, match="ATT_FX_E_RANGE"):
        raise_for_status(names.C["ATT_FX_E_RANGE"], "q")
    with pytest.raises(InvalidArgument, match="integ: unknown method"):
        raise_for_status(names.C["ATT_E_INTEG_METHOD"], "integ")
    raise_for_status(0, "ok")
    raise_for_status(1, "a result, not an error")


def test_methods_are_the_librarys() -> None:
    assert set(core.METHODS) == set(names.method_names())  # the Literal type spells out the library's names
    for m in core.METHODS:
        assert names.method_names()[core.method_code(m)] == m
        assert names.method_code(m) == names.C["ATT_METHOD_" + m.upper().replace("-", "_")]
    for m in fixedpoint.METHODS:  # the fixed-point port: the same numbers
        key = m.upper().replace("-", "_")
        assert names.C["ATT_FX_" + key] == names.C["ATT_METHOD_" + key]
    assert set(fixedpoint.METHODS) == set(core.INCREMENT_METHODS)
    # samples per update: the library's count, and the reference's math agrees
    assert {m: names.samples_per_update(m) for m in core.INCREMENT_METHODS} == reference.FRAME
    assert names.samples_per_update("rk4") == 2  # a step's midpoint and end rows
    assert attitude_c.METHODS is core.METHODS


def test_link_results_are_the_librarys() -> None:
    for r in Result:
        assert names.C["ATT_LINK_" + r.name] == r.value


def test_no_status_code_is_typed_again_in_python() -> None:
    """The old copies (−20.. in core, −40.. in tlc2543, −60.. in the link ends, −80.. in
    fixedpoint, −1.. in errors) are gone: no dict in the package is keyed by a negative
    integer literal; status meanings are keyed by C names."""
    hits = []
    for f in sorted((ROOT / "attitude_c").rglob("*.py")):
        for node in ast.walk(ast.parse(f.read_text())):
            if isinstance(node, ast.Dict):
                for k in node.keys:
                    if isinstance(k, ast.UnaryOp) and isinstance(k.op, ast.USub) and isinstance(k.operand, ast.Constant):
                        hits.append(f"{f.relative_to(ROOT)}:{k.lineno}")
    assert not hits, hits


def _library_status_codes() -> dict[str, int]:
    """The status codes the library's own headers define (csrc/include/attitude; not the
    host twins' codes), by their text."""
    lib_headers = [h for h in HEADERS if h.parent.name == "attitude"]
    out: dict[str, int] = {}
    for h in lib_headers:
        text = re.sub(r"/\*.*?\*/", " ", h.read_text(), flags=re.DOTALL)
        out.update({m[0]: int(m[1]) for m in re.findall(r"\b(\w+_E_\w+)\s*=\s*(-\d+)", text)})
    return out


def test_att_status_str_names_every_code_of_the_headers() -> None:
    """att_status_str (csrc/src/common.c, one table): every code of every module's header
    has its own text; csrc/tests/test_status.c (run by test_c_programs.py under the
    sanitizers) lists exactly these codes and checks the same in C."""
    from attitude_c._lib import ffi_lib

    codes = _library_status_codes()
    assert len(codes) > 50 and all(v < 0 for v in codes.values())
    assert codes == {k: v for k, v in _header_enums().items() if k in codes}
    listed = re.findall(r"CODE\(([A-Z][A-Z0-9_]+)\)", (ROOT / "csrc" / "tests" / "test_status.c").read_text())
    assert sorted(listed) == sorted(codes) and len(set(listed)) == len(listed)
    for precision in ("f64", "f32"):
        ffi, lib = ffi_lib(precision)
        texts = {k: ffi.string(lib.att_status_str(v)).decode() for k, v in codes.items()}
        assert not [k for k, t in texts.items() if t in ("unknown status", "ok", "")], texts
        assert len(set(texts.values())) == len(texts), texts  # a text names its code
        assert {names.status_text(v) for v in codes.values()} == set(texts.values())


def _host_status_codes() -> dict[str, int]:
    """The status codes the host twins' headers define (csrc/host: outside the library)."""
    out: dict[str, int] = {}
    for h in (h for h in HEADERS if h.parent.name == "host"):
        text = re.sub(r"/\*.*?\*/", " ", h.read_text(), flags=re.DOTALL)
        out.update({m[0]: int(m[1]) for m in re.findall(r"\b(\w+_E_\w+)\s*=\s*(-\d+)", text)})
    return out


def test_every_code_python_can_see_has_a_text_of_its_own() -> None:
    """Every status code the package knows (names.C: the library's and the host
    twins', which the C twins' batch calls return) has its own text: the library's
    from att_status_str, the twins' from devm_status_str (csrc/host/devmodel.c; the
    twins live outside the library); csrc/tests/test_devmodel.c (run by
    test_c_programs.py) lists exactly the twins' codes and checks the same in C."""
    import pytest

    from attitude_c.errors import AttitudeError
    from attitude_c.names import raise_for_status

    host, library = _host_status_codes(), _library_status_codes()
    assert host and set(host).isdisjoint(library)
    listed = re.findall(r"HOST_CODE\(([A-Z][A-Z0-9_]+)\)", (ROOT / "csrc" / "tests" / "test_devmodel.c").read_text())
    assert sorted(listed) == sorted(host) and len(set(listed)) == len(listed)
    codes = {k: v for k, v in names.C.items() if v < 0 and "_E_" in k}
    assert set(codes) == set(host) | set(library)
    texts = {k: names.status_text(v) for k, v in codes.items()}
    assert not [k for k, t in texts.items() if t in ("unknown status", "ok", "")], texts
    assert len(set(texts.values())) == len(texts), texts  # a text names its code
    for name, v in host.items():  # without a module's own meaning: the twin's text and its name
        with pytest.raises(AttitudeError, match=rf"^x: {re.escape(texts[name])} \(status {v}, {name}\)$"):
            raise_for_status(v, "x")


def test_python_error_texts_are_the_librarys() -> None:
    import pytest

    from attitude_c.errors import AttitudeError
    from attitude_c.names import raise_for_status

    for name, (_, text) in names.STATUS.items():
        assert text == names.status_text(names.C[name]) != "unknown status", name
    assert set(names.STATUS) <= set(_library_status_codes())
    # a code without a Python meaning of its own: still the library's text
    with pytest.raises(AttitudeError, match=r"adc: TLC2543: EOC did not rise .*TLC2543_E_EOC_TIMEOUT"):
        raise_for_status(names.C["TLC2543_E_EOC_TIMEOUT"], "adc")
    with pytest.raises(AttitudeError, match=r"x: unknown status \(status -999\)"):
        raise_for_status(-999, "x")
