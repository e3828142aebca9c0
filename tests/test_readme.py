"""The README is a short front door: its own-part examples run as written (in a scratch folder),
and neither it nor docs/ points at anything users lack or speaks to the people who wrote it."""

import re
import warnings

import pytest

from mavac.config import ROOT

README = ROOT / "README.md"
PAGES = [README, *sorted((ROOT / "docs").glob("*.md"))]
MAX_README_LINES = 220

# Paths that exist only on the machine the package was written on.
UNREACHABLE = ("/work/", "../shared", "shared/", "DESIGN.md", "ENVIRONMENT.md")
# Notes addressed to the team rather than to users: issue numbers, sessions, rounds, to-dos.
TEAM_NOTES = (r"\bthe issue\b", r"\bissue\s*#?\d+", r"\bsessions?\b", r"\bcoordinator\b", r"\bthis round\b",
              r"\bthe team\b", r"\bTODO\b", r"\bFIXME\b", r"\bXXX\b", r"did not finish", r"not yet verified",
              r"\bwe (?:did not|didn't|have not|haven't) (?:finish|run|had time)")
NUMBERS = {"ten": 10, "eleven": 11, "twelve": 12, "thirteen": 13, "fourteen": 14, "fifteen": 15}


def _blocks():
    text = README.read_text()
    section = text.split("## Use it on your own machine or part", 1)[1].split("\n## ", 1)[0]
    return re.findall(r"```python\n(.*?)```", section, re.S)


def test_readme_examples_run(tmp_path, monkeypatch, capsys):
    blocks = _blocks()
    assert len(blocks) == 2
    monkeypatch.chdir(tmp_path)
    for code in blocks:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the examples' low-coverage or repair warnings are fine here
            exec(compile(code, "README.md", "exec"), {"__name__": "readme"})
    out = capsys.readouterr().out
    assert "(raycast visibility)" in out and "setup 1:" in out
    for name in ("cabinet_plan.json", "cabinet_plan.html", "dome_setups.json", "dome_setups.html"):
        assert (tmp_path / name).stat().st_size > 0


def test_readme_is_a_short_front_door():
    lines = README.read_text().splitlines()
    assert len(lines) <= MAX_README_LINES, f"README.md has {len(lines)} lines; move detail to docs/"
    headings = [line for line in lines if line.startswith("## ")]
    for name in ("## Install", "## Two commands", "## Command line", "## Use it on your own machine or part",
                 "## Results: paper vs. ours", "## Read more"):
        assert name in headings


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_pages_point_at_nothing_users_lack(page):
    text = page.read_text()
    found = [s for s in UNREACHABLE if s in text]
    assert not found, f"{page.name} refers to {found}, which users of the package do not have"


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_pages_do_not_address_the_team(page):
    text = page.read_text()
    found = [m.group(0) for pattern in TEAM_NOTES for m in re.finditer(pattern, text, re.I)]
    assert not found, f"{page.name} holds notes to the team, not to users: {found}"


def _notebook_counts(page):
    pattern = r"\b(" + "|".join(NUMBERS) + r")\b(?:\s+\w+)?\s+notebooks"
    return [NUMBERS[w] for w in re.findall(pattern, page.read_text().lower())]


def test_pages_count_the_notebooks_there_are():
    assert _notebook_counts(README), "the README says how many notebooks there are"
    said = {n for page in PAGES for n in _notebook_counts(page)}
    assert said == {len(list((ROOT / "notebooks").glob("*.ipynb")))}
