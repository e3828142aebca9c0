"""docs/: the results page and the README's results table are generated from the committed CSVs
and current; the architecture page names every module on disk (and no other); links resolve."""

import re
from pathlib import Path

import pandas as pd
import pytest

from mavac import docs_results
from mavac.experiments import mavac_online as mon
from mavac.config import ROOT

DOCS = ROOT / "docs"
PACKAGE = ROOT / "mavac"
REGENERATE = "stale: run `python -m mavac.docs_results`"


def test_results_page_is_current():
    assert (DOCS / "results.md").read_text() == docs_results.results_page(), REGENERATE


def test_readme_results_block_is_current():
    readme = (ROOT / "README.md").read_text()
    assert docs_results.START in readme and docs_results.END in readme
    assert docs_results.replace_block(readme, docs_results.readme_block()) == readme, REGENERATE


def test_readme_times_block_is_current():
    readme = (ROOT / "README.md").read_text()
    block = docs_results.times_block()
    assert "Not run" not in block and "| **total** |" in block
    assert docs_results.replace_block(readme, block, start=docs_results.TIMES_START,
                                      end=docs_results.TIMES_END) == readme, REGENERATE


def test_times_block_in_minutes_and_not_run_without_its_csv(tmp_path, monkeypatch):
    monkeypatch.setattr(docs_results, "RESULTS_DIR", tmp_path)
    assert "*Not run: `data/results/reproduce_times.csv` is not there" in docs_results.times_block()
    pd.DataFrame(dict(notebook=["05_online_cleaning", "total"], wall_s=[90.0, 120.0], cpu_s=[180.0, 180.0])).to_csv(
        tmp_path / "reproduce_times.csv", index=False)
    block = docs_results.times_block()
    assert "| 05_online_cleaning | 1.5 | 3.0 |" in block and "| **total** | 2.0 | 3.0 |" in block
    with pytest.raises(ValueError, match="times:start"):
        docs_results.replace_block("no markers", block, start=docs_results.TIMES_START, end=docs_results.TIMES_END)


def test_every_section_has_data_and_robot_results_say_simulated():
    secs = docs_results.sections()
    assert [s for s in secs if "Not run" in s.body] == []
    for s in secs:
        if s.anchor in ("mavac-table-2", "kabir-table-vii", "kabir-execution"):
            assert "SIMULATED" in s.item and "**SIMULATED**" in s.body
    assert len({s.anchor for s in secs}) == len(secs)


def test_missing_csv_or_column_says_not_run(tmp_path, monkeypatch):
    pd.DataFrame({"machine": ["test_bench"], "trial": [1]}).to_csv(tmp_path / "mavac_table2.csv", index=False)
    monkeypatch.setattr(docs_results, "RESULTS_DIR", tmp_path)
    secs = {s.anchor: s for s in docs_results.sections()}
    assert "`data/results/mavac_table1.csv` is not there" in secs["mavac-table-1"].body
    assert "no column `reading`" in secs["mavac-table-2"].body
    assert secs["kabir-table-ii"].ours == "not run"
    assert "not run" in docs_results.readme_block(list(secs.values()))


def test_table2_has_one_column_per_variant_and_the_sensitivity_beside_it(tmp_path, monkeypatch):
    trials = pd.DataFrame([dict(reading=r, offline=o, scene=sc, trial=t, seed=t, heaps=10, cleaned=c, uncleaned=10 - c,
                                cleaning_pct=10.0 * c, sim_time_s=600.0, open_heaps=8, open_cleaned=min(c, 8),
                                enclosed_heaps=2, enclosed_cleaned=max(c - 8, 0))
                           for r, o, base in (("paper", "hpr", 8), ("paper", "raycast", 6), ("authors", "hpr", 4))
                           for sc in ("test_bench", "sanding_milling") for t, c in ((1, base - 1), (2, base + 1))])
    trials.to_csv(tmp_path / "mavac_table2_trials.csv", index=False)
    mon.table2(trials).to_csv(tmp_path / "mavac_table2.csv", index=False)
    pd.DataFrame([dict(dimension="nominal", value=None, seeds="1 2", heaps=156.0, cleaning_pct=70.0, cleaning_pct_min=60.0,
                       cleaning_pct_max=80.0, unseen=3.5)]).to_csv(tmp_path / "mavac_table2_sensitivity.csv", index=False)
    monkeypatch.setattr(docs_results, "RESULTS_DIR", tmp_path)
    part = docs_results.mavac_table2()
    assert "ours, paper's text, HPR offline | ours, paper's text, ray casting offline |" in part.body
    assert "| paper-style mean, all trials of both tests | 84.0 % | 80.0 % (70.0-90.0) | 60.0 % (50.0-70.0) |" in part.body
    assert "| nominal | — | 1 2 | 156 | 70.0 % (60.0-80.0) | 3.5 |" in part.body
    assert "| enclosed heaps, both tests | — | 25.0 % of 2 heaps/trial |" in part.body
    assert "authors' code (4a4038c), HPR offline 40.0 % (test bench 40.0 %, sanding + milling 40.0 %)" in part.ours


def _modules_on_disk() -> set[str]:
    return {p.relative_to(PACKAGE).as_posix() for p in PACKAGE.rglob("*.py")
            if p.name != "__init__.py" and "__pycache__" not in p.parts}


def _modules_on_page() -> set[str]:
    text = (DOCS / "architecture.md").read_text()
    return set(re.findall(r"^- `([\w/]+\.py)`:", text, re.M))


def test_architecture_names_every_module():
    missing = sorted(_modules_on_disk() - _modules_on_page())
    assert not missing, f"docs/architecture.md lacks a line for: {missing}"


def test_architecture_names_no_module_that_is_gone():
    gone = sorted(_modules_on_page() - _modules_on_disk())
    assert not gone, f"docs/architecture.md describes modules not in mavac/: {gone}"


def _links(page: Path):
    for target in re.findall(r"\]\(([^)\s]+)\)", page.read_text()):
        if not re.match(r"[a-z]+:", target):
            yield target


@pytest.mark.parametrize("page", [ROOT / "README.md", *sorted(DOCS.glob("*.md"))], ids=lambda p: p.name)
def test_relative_links_resolve(page):
    broken = []
    for target in _links(page):
        path, _, anchor = target.partition("#")
        dest = (page.parent / path).resolve() if path else page
        if not dest.exists():
            broken.append(target)
        elif anchor and dest.suffix == ".md":
            text = dest.read_text()
            slugs = {re.sub(r"[^\w\- ]", "", h.strip().lower()).replace(" ", "-")
                     for h in re.findall(r"^#+ (.*)$", text, re.M)}
            if f'id="{anchor}"' not in text and anchor not in slugs:
                broken.append(target)
    assert not broken, f"{page.name}: links that lead nowhere: {broken}"
