"""Figures from one source (issue 31, item 4).

Every benchmark writes its table into docs/bench/NAME.md, closed by a stamp line: the
SHA-256 of the text above it (toolchain/tasks/core.py, BENCH_STAMP). A hand edit breaks
the stamp; docs/benchmarks.md is their reassembly, nothing else. Prose refers to those
tables instead of retyping their numbers: a three-decimal figure typed
FIGURE_LIMIT times or more across the docs' prose is one typed too often."""

from __future__ import annotations

import re
from collections import Counter
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
    text = re.sub(r"^(```|~~~).*?^\1", "", text, flags=re.S | re.M)
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


def test_no_figure_is_typed_three_times_in_the_docs() -> None:
    bad = retyped_figures(PROSE)
    assert bad == {}, ("three-decimal figures typed %d times or more in the docs' prose (refer to "
                       "docs/bench/ instead): %s" % (FIGURE_LIMIT, bad))
