"""The ``attitude`` command's help (issue 27 item 12): docs/cli.md lists every
subcommand the parser registers, and no help text -- a subcommand's summary,
description, epilog, argument groups, option help -- carries reStructuredText
markup (``--help`` prints it as it is)."""

from __future__ import annotations

import argparse
import re
from collections.abc import Iterator
from pathlib import Path

import pytest

from attitude_c.cli import build_parser

ROOT = Path(__file__).resolve().parents[1]

#: reStructuredText markup: ``literal``, :role:`target`, `interpreted text`
MARKUP = re.compile(r"``|:[a-z]+(:[a-z]+)*:`|`[^`\n]+`")


def _subcommands() -> argparse._SubParsersAction:
    parser = build_parser()
    return next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))


SUB = _subcommands()


def _texts(name: str) -> Iterator[tuple[str, str]]:
    """(where, text) of every help text of subcommand ``name``."""
    summary = next(a.help for a in SUB._choices_actions if a.dest == name)
    yield "summary", summary or ""
    p = SUB.choices[name]
    yield "description", p.description or ""
    yield "epilog", p.epilog or ""
    for g in p._action_groups:
        yield f"group {g.title!r}", f"{g.title or ''} {g.description or ''}"
    for a in p._actions:
        yield " ".join(a.option_strings) or a.dest, a.help or ""


def test_docs_cli_lists_every_subcommand() -> None:
    text = (ROOT / "docs" / "cli.md").read_text(encoding="utf-8")
    table = text.split("## The subcommands", 1)[1].split("\n## ", 1)[0]
    listed = re.findall(r"^\| `([a-z0-9-]+)` \|", table, flags=re.MULTILINE)
    assert sorted(listed) == sorted(SUB.choices), "docs/cli.md's table of subcommands is not the parser's"
    assert len(listed) == len(set(listed))


def test_the_markup_pattern_finds_markup() -> None:
    found = [bool(MARKUP.search(t)) for t in ("``attitude demo``", ":mod:`attitude_c.reference`",
                                              "an `attitude simulate` option", "a plain 'quoted' text",
                                              "dt: the rate's period (s)", "ΩT, 5–95 %")]
    assert found == [True, True, True, False, False, False]


@pytest.mark.parametrize("name", sorted(SUB.choices))
def test_help_texts_have_no_restructuredtext_markup(name: str) -> None:
    bad = [(where, m.group(0)) for where, t in _texts(name) for m in MARKUP.finditer(t)]
    assert bad == [], f"attitude {name} --help shows markup: {bad[:5]}"
