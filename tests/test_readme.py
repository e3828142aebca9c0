"""The README's own-part examples run as written (in a scratch folder)."""

import re
import warnings

from mavac.config import ROOT


def _blocks():
    text = (ROOT / "README.md").read_text()
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
