"""Figures from one source (issue 31, item 4).

Every benchmark writes its table into docs/bench/NAME.md, closed by a stamp line: the
SHA-256 of the text above it (toolchain/tasks/core.py, BENCH_STAMP). A hand edit breaks
the stamp; docs/benchmarks.md is their reassembly, nothing else. Prose refers to those
tables instead of retyping their numbers: a three-decimal figure typed
FIGURE_LIMIT times or more across the docs' prose is one typed too often. The README's
headline figures are rounded from the tables, and checked against them here."""

from __future__ import annotations

import math
import re
from collections import Counter
from decimal import ROUND_HALF_UP, Decimal
from pathlib import Path

import pytest
from conftest import ROOT

from toolchain.tasks import core

PARTS = sorted((ROOT / "docs" / "bench").glob("*.md"))
#: The prose checked for retyped figures: every page of docs/ (docs/bench/ and the generated
#: docs/benchmarks.md are the tables themselves) and the README.
PROSE = [p for p in sorted((ROOT / "docs").glob("*.md")) if p.name != "benchmarks.md"] + [ROOT / "README.md"]
#: A figure with three decimals (2.023, 0.355; not 1.5 or 10, not part of 1.2.3 or x1.234).
FIGURE = re.compile(r"(?<![\w.])\d+\.\d{3}(?!\d)")
#: Typed this many times across PROSE, a figure is retyped: name it once, refer to the table.
FIGURE_LIMIT = 3


@pytest.mark.parametrize("part", PARTS, ids=lambda p: p.name)
def test_bench_tables_are_as_generated(part: Path) -> None:
    """The stamp of docs/bench/NAME.md matches its text: not edited since `invoke bench` wrote it."""
    assert core.unstamped(part.read_text()) is not None, (
        f"{part.relative_to(ROOT)} was edited by hand (its stamp does not match): edit bench/"
        f"{part.stem}.py and run `invoke bench --only {part.stem}`")


def test_benchmarks_md_is_the_reassembly_of_the_tables() -> None:
    assert PARTS
    assert core.BENCH_DOC.read_text() == core.bench_doc_text(), \
        "docs/benchmarks.md differs from docs/bench/*.md: run `invoke bench --only assemble`"


def test_the_stamp_catches_an_edit() -> None:
    text = PARTS[0].read_text()
    assert core.unstamped(text.replace("|", "| ", 1)) is None
    assert core.unstamped(core.unstamped(text) or "") is None  # the stamp removed


def prose(text: str) -> str:
    """A Markdown page without its fenced code blocks and inline code (commands, names)."""
    text = re.sub(r"^(```|~~~).*?^\1", "", text, flags=re.DOTALL | re.MULTILINE)
    return re.sub(r"`(?:[^`\n]|\n(?![ \t]*\n))*`", "", text)  # a span may wrap, not cross a paragraph


def retyped_figures(pages: list[Path]) -> dict[str, dict[str, int]]:
    """Figures typed FIGURE_LIMIT times or more across ``pages``: figure -> {page: count}."""
    where: dict[str, Counter[str]] = {}
    for page in pages:
        for fig in FIGURE.findall(prose(page.read_text())):
            where.setdefault(fig, Counter())[str(page.relative_to(ROOT))] += 1
    return {f: dict(c) for f, c in sorted(where.items()) if sum(c.values()) >= FIGURE_LIMIT}


def test_retyped_figures_are_found() -> None:
    """The check itself, on a page written for it."""
    page = ("2.023 twice: 2.023; thrice 2.023, `2.023` (code), `a\n2.023` (code, wrapped), 1.5, 10.25, "
            "v1.234.5\n```\n2.023\n```\n")
    assert FIGURE.findall(prose(page)) == ["2.023", "2.023", "2.023"]


def constants() -> set[str]:
    """Figures that are not measurements: the filter's setting defaults (read from the compiled
    library) and the Allan floor's factor sqrt(2 ln 2 / pi) = 0.664; a page may name them freely."""
    from attitude_c.ahrs_filter import default_settings

    values = [v for v in default_settings().values() if isinstance(v, float)]
    return {f"{v:.3f}" for v in values if f"{v:.3f}" != "0.000"} | {f"{math.sqrt(2 * math.log(2) / math.pi):.3f}"}


def test_no_figure_is_typed_three_times_in_the_docs() -> None:
    bad = {f: c for f, c in retyped_figures(PROSE).items() if f not in constants()}
    assert bad == {}, (f"three-decimal figures typed {FIGURE_LIMIT} times or more in the docs' prose "
                       f"(refer to docs/bench/ instead): {bad}")


# -- the README's headline figures: rounded from the generated tables, checked here --------

def _row(part: str, label: str) -> list[str]:
    """The cells after ``label`` of the table row of docs/bench/PART.md whose first cell it is."""
    for line in (ROOT / "docs" / "bench" / f"{part}.md").read_text().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if cells[0] == label:
            return cells[1:]
    raise AssertionError(f"docs/bench/{part}.md has no row {label!r}")


def _r2(figure: str) -> str:
    """A table's figure as the README rounds it: two decimals, half up (2.225 -> 2.23)."""
    return str(Decimal(figure).quantize(Decimal("0.01"), rounding=ROUND_HALF_UP))


def _readme_claims() -> list[str]:
    """Each README sentence that quotes a benchmark, with the figures of the tables today."""
    ours = [_r2(f) for f in _row("broad", "all")[0].split(" / ")]
    vqf = [_r2(f) for f in _row("broad", "all")[2].split(" / ")]
    groups = {g: (_r2(_row("broad", g)[0].split(" / ")[0]), _r2(_row("broad", g)[2].split(" / ")[0]))
              for g in ("undisturbed", "disturbed")}
    acc5 = _row("broad_timing", "mag_delay = 0.013, acc_delay = 5 ms (scan, scored with the reference)")
    lag = _row("broad_timing", "this filter, `sensor_delay` = 2.4 ms")
    vqf_lag = _row("broad_timing", "VQF, output turned forward by 2.4 ms")
    return [
        (f"this filter {ours[0]}° total, {ours[1]}° heading, {ours[2]}° inclination (VQF, the strongest open "
         f"filter, on the same trials: {vqf[0]}°, {vqf[1]}°, {vqf[2]}°), ahead of VQF in both groups "
         f"(undisturbed {groups['undisturbed'][0]}° vs {groups['undisturbed'][1]}°, disturbed "
         f"{groups['disturbed'][0]}° vs {groups['disturbed'][1]}°)"),
        f"{_row('broad', 'f32')[0]} ARMv4T instructions per sample in float",
        f"declared with its accelerometer's ~5 ms, {_r2(acc5[0])}° total",
        (f"this filter scores {_r2(lag[0])}° total, {_r2(lag[2])}° inclination and VQF {_r2(vqf_lag[0])}°, "
         f"{_r2(vqf_lag[2])}°"),
    ]


def test_readme_headline_figures_are_the_tables() -> None:
    """The README keeps one headline figure per claim, rounded from docs/bench/ (broad, broad_timing)."""
    readme = " ".join((ROOT / "README.md").read_text().split())
    for claim in _readme_claims():
        assert claim in readme, f"README.md should say (from docs/bench/): {claim!r}"
