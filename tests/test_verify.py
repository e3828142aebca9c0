"""mavac.verify: the declared tables match the notebooks and the committed files; the comparisons
name what differs; committed results are not older than their code; and a fast-mode notebook
run gives identical files twice, with a CPU hog beside one run."""

import fnmatch
import json
import os
import re
import subprocess
import sys
import warnings

import numpy as np
import pandas as pd
import pytest

from mavac import verify as V
from mavac.config import ROOT


def _code(path) -> str:
    cells = json.loads(path.read_text())["cells"]
    return "\n".join("".join(c["source"]) for c in cells if c["cell_type"] == "code")


def _written_by(source: str) -> set[str]:
    """Result keys a notebook's source writes: ``results_dir() / "x.csv"`` (f-string fields
    become ``*``) and the instances folder of ``write_table2_instances``."""
    names = re.findall(r'results_dir\(\)\s*/\s*f?"([^"]+)"', source)
    keys = {"results/" + re.sub(r"\{[^}]*\}", "*", n) for n in names}
    return keys | ({"instances/kabir_table2_*.npz"} if "instances_dir()" in source else set())


# ---------------------------------------------------------------- declarations


def test_outputs_table_is_what_the_notebooks_write():
    books = V.notebooks()
    assert list(V.OUTPUTS) == list(books)
    for number, path in books.items():
        declared, written = V.OUTPUTS[number], _written_by(_code(path))
        assert [w for w in written if not any(fnmatch.fnmatchcase(w, d) for d in declared)] == [], path.name
        assert [d for d in declared if not any(fnmatch.fnmatchcase(w, d) for w in written)] == [], path.name


def test_every_committed_result_has_one_writer():
    committed = V.result_files(ROOT)
    assert committed, "no committed results found"
    assert [k for k in committed if V.owner(k) is None] == []


def test_declared_wall_clock_columns_exist_in_the_committed_headers():
    committed = V.result_files(ROOT)
    for (key, column), reason in V.WALL_CLOCK.items():
        assert reason
        if key in committed:  # reproduce_times.csv appears with the first `make reproduce`
            assert column in pd.read_csv(committed[key], nrows=0).columns, (key, column)
    for (key, column), (flag, reason) in V.ONLY_WHERE_SUCCEEDED.items():
        assert reason and {column, flag} <= set(pd.read_csv(committed[key], nrows=0).columns), (key, column)


def test_docs_list_every_declared_column_and_tolerance():
    page = (ROOT / "docs" / "reproduce.md").read_text()
    for key, column in [*V.WALL_CLOCK, *V.RELATIVE_TOLERANCE, *V.ONLY_WHERE_SUCCEEDED]:
        assert f"`{column}`" in page and key.split("/")[1] in page, (key, column)


def test_unknown_notebook_names_the_parameter():
    assert V.check_notebook("only", "5") == "05"
    with pytest.raises(ValueError, match="only must be a notebook number"):
        V.check_notebook("only", "99")
    with pytest.raises(ValueError, match="only must be"):
        V.selected({}, {}, only="x")


# ---------------------------------------------------------------- comparisons


def _csv(path, text):
    path.write_text(text)
    return path


def test_compare_csv_names_rows_and_columns(tmp_path):
    a = _csv(tmp_path / "a.csv", "k,x,seconds\n1,0.5,3.1\n2,0.7,4\n3,1,5\n")
    assert V.compare_csv(a, a) is None
    b = _csv(tmp_path / "b.csv", "k,x,seconds\n1,0.5,9.9\n2,0.71,4\n3,2,5\n")
    assert V.compare_csv(a, b) == "3 rows, columns x, seconds"
    assert V.compare_csv(a, b, ignore={"seconds"}) == "2 rows, columns x"
    assert V.compare_csv(a, b, ignore={"seconds", "x"}) is None
    assert V.compare_csv(a, b, ignore={"seconds"}, rtol={"x": 0.02}) == "1 rows, columns x"


def test_compare_csv_compares_declared_columns_only_where_a_run_succeeded(tmp_path):
    a = _csv(tmp_path / "a.csv", "k,err,success\n1,0.5,True\n2,2287.12,False\n3,0.1,False\n")
    b = _csv(tmp_path / "b.csv", "k,err,success\n1,0.5,True\n2,2521.33,False\n3,0.2,True\n")
    assert V.compare_csv(a, b) == "2 rows, columns err, success"
    assert V.compare_csv(a, b, when={"err": "success"}) == "1 rows, columns err, success"  # row 3 succeeded once
    c = _csv(tmp_path / "c.csv", "k,err,success\n1,0.6,True\n2,9.0,False\n3,0.1,False\n")
    assert V.compare_csv(a, c, when={"err": "success"}) == "1 rows, columns err"  # a succeeded row still counts
    d = _csv(tmp_path / "d.csv", "k,err,success\n1,0.5,True\n2,9.0,False\n3,7.0,False\n")
    assert V.compare_csv(a, d, when={"err": "success"}) is None


def test_icp_trials_declare_their_diverged_errors():
    _, _, when = V.rules("results/kabir_icp_trials.csv")
    assert when == {c: "success" for c in ("translation_error_m", "rotation_error_rad", "adds_m")}
    assert V.rules("results/kabir_icp.csv")[2] == {}


def test_compare_csv_header_length_and_formatting(tmp_path):
    a = _csv(tmp_path / "a.csv", "k,x\n1,2\n2,3\n")
    assert V.compare_csv(a, _csv(tmp_path / "b.csv", "k,x\n1,2\n")) == "1 rows, columns - (2 rows fresh, 1 committed)"
    assert V.compare_csv(a, _csv(tmp_path / "c.csv", "k,y\n1,2\n2,3\n")) == "2 rows, columns y, x"
    assert V.compare_csv(a, _csv(tmp_path / "d.csv", '"k",x\n1,2\n2,3\n')) == "0 rows (bytes differ, values equal)"


def test_compare_json_names_fields(tmp_path):
    base = {"C": 0.5, "poses": [{"q": [1.0, 2.0], "kind": "guard"}, {"q": [3.0, 4.0], "kind": "nos"}], "n": 3}
    changed = {"C": 0.5, "poses": [{"q": [1.0, 2.5], "kind": "guard"}, {"q": [3.0, 4.5], "kind": "nos"}], "n": 3.0}
    (tmp_path / "a.json").write_text(json.dumps(base))
    (tmp_path / "b.json").write_text(json.dumps(changed))
    a, b = tmp_path / "a.json", tmp_path / "b.json"
    assert V.compare_json(a, a) is None
    assert V.compare_json(a, b) == "3 values, fields n, poses[].q[]"
    assert V.compare_json(a, b, ignore={"n"}, rtol={"poses[].q[]": 0.2}) is None
    (tmp_path / "c.json").write_text(json.dumps({"C": 0.5}))
    assert V.compare_json(a, tmp_path / "c.json") == "7 values, fields n, poses[].kind, poses[].q[]"


def test_compare_npz_names_arrays(tmp_path):
    np.savez(tmp_path / "a.npz", cover=np.eye(3, dtype=bool), costs=np.arange(3.0))
    np.savez(tmp_path / "b.npz", cover=np.eye(3, dtype=bool), costs=np.arange(3.0) + 1)
    assert V.compare_npz(tmp_path / "a.npz", tmp_path / "a.npz") is None
    assert V.compare_npz(tmp_path / "a.npz", tmp_path / "b.npz") == "arrays costs"


def _tree(root, files: dict):
    for rel, text in files.items():
        (root / rel).parent.mkdir(parents=True, exist_ok=True)
        (root / rel).write_text(text)
    return root


def test_verify_reports_every_file_and_main_exits_nonzero(tmp_path, capsys):
    same, t6 = "a,b\n1,2\n", "object,seconds,nodes\nx,0.1,5\n"
    fresh = _tree(tmp_path / "fresh", {"data/results/machines.csv": same, "data/results/kabir_table6.csv": t6,
                                       "data/results/parts.csv": "a\n2\n", "data/results/kabir_fig9.csv": same,
                                       "data/results/provenance.json": "{}"})
    committed = _tree(tmp_path / "committed", {"data/results/machines.csv": same,
                                               "data/results/kabir_table6.csv": t6.replace("0.1", "0.3"),
                                               "data/results/parts.csv": "a\n1\n",
                                               "data/results/kabir_table5.csv": same})
    lines = [o.line() for o in V.verify(fresh, committed)]
    assert lines == ["data/results/kabir_fig9.csv: extra", "data/results/kabir_table5.csv: missing",
                     "data/results/kabir_table6.csv: identical", "data/results/machines.csv: identical",
                     "data/results/parts.csv: differs: 1 rows, columns a"]
    assert [o.path for o in V.verify(fresh, committed, only="01")] == ["data/results/machines.csv",
                                                                       "data/results/parts.csv"]
    assert V.main(["--fresh", str(fresh), "--committed", str(committed)]) == 1
    assert "5 files: 2 identical, 1 differs, 1 missing, 1 extra" in capsys.readouterr().out
    assert V.main(["--fresh", str(fresh), "--committed", str(committed), "--only", "08"]) == 1
    assert V.main(["--fresh", str(fresh), "--committed", str(fresh), "--only", "01"]) == 0
    assert V.main(["--fresh", str(fresh), "--committed", str(committed), "--only", "13"]) == 2
    assert "only must be a notebook number" in capsys.readouterr().err


def test_times_rows_are_replaced_and_totalled(tmp_path):
    times = V.merged_times(None, dict(notebook="05_online", wall_s=10.0, cpu_s=9.0))
    times = V.merged_times(V.with_total(times, 12.0), dict(notebook="01_machines", wall_s=2.0, cpu_s=1.5))
    times = V.merged_times(times, dict(notebook="05_online", wall_s=11.0, cpu_s=8.0))
    total = V.with_total(times, 20.0)
    assert total.to_dict("list") == {"notebook": ["01_machines", "05_online", "total"], "wall_s": [2.0, 11.0, 20.0],
                                     "cpu_s": [1.5, 8.0, 9.5]}
    path = tmp_path / "data" / "results" / "reproduce_times.csv"
    path.parent.mkdir(parents=True)
    times.to_csv(path, index=False)
    V.finish_run(tmp_path, 0.0, tmp_path / "executed")
    assert pd.read_csv(path)["notebook"].tolist() == ["01_machines", "05_online", "total"]
    with pytest.raises(ValueError, match="out: no data/results/reproduce_times.csv"):
        V.finish_run(tmp_path / "empty", 0.0, tmp_path / "executed")


# ---------------------------------------------------------------- staleness


def test_notebook_dependencies_follow_imports():
    deps = V.notebook_dependencies("05")
    assert {"notebooks/05_online_cleaning.ipynb", "mavac/__init__.py", "mavac/experiments/__init__.py",
            "mavac/experiments/mavac_online.py", "mavac/cache.py", "mavac/config.py"} <= set(deps)
    assert "mavac/experiments/kabir_gpr.py" not in deps
    assert "data/paper_values.csv" in V.notebook_dependencies("01")  # via mavac.paper
    assert all((ROOT / d).is_file() for d in deps)


def _git(repo, *args) -> str:
    env = dict(GIT_AUTHOR_NAME="t", GIT_AUTHOR_EMAIL="t@t", GIT_COMMITTER_NAME="t", GIT_COMMITTER_EMAIL="t@t",
               GIT_CONFIG_GLOBAL="/dev/null", GIT_CONFIG_NOSYSTEM="1", PATH="/usr/bin:/bin")
    return subprocess.run(["git", "-C", str(repo), *args], capture_output=True, text=True, check=True,
                          env=env).stdout.strip()


def _commit(repo, path, text) -> str:
    (repo / path).write_text(text)
    _git(repo, "add", path)
    _git(repo, "commit", "-q", "-m", path)
    return _git(repo, "rev-parse", "HEAD")


def test_staleness_on_a_temporary_repository(tmp_path):
    _git(tmp_path, "init", "-q")
    first = _commit(tmp_path, "code.py", "x = 1\n")
    deps = {"01": ["code.py"]}
    prov = {"data/results/a.csv": dict(notebook="01", commit=first)}
    assert V.stale_results(tmp_path, prov, deps) == {}
    _commit(tmp_path, "other.txt", "unrelated\n")  # a change elsewhere keeps the result current
    assert V.stale_results(tmp_path, prov, deps) == {}
    second = _commit(tmp_path, "code.py", "x = 2\n")
    stale = V.stale_results(tmp_path, prov, deps)
    assert list(stale) == ["data/results/a.csv"] and second in stale["data/results/a.csv"]
    assert V.stale_results(tmp_path, {"r.csv": dict(notebook="01", commit=second)}, deps) == {}
    assert V.stale_results(tmp_path, {"r.csv": dict(notebook="01", commit="f" * 40)}, deps) != {}
    assert V.stale_results(tmp_path, {"r.csv": dict(notebook="01", commit=None)}, deps) != {}
    assert "no longer exists" in V.stale_results(tmp_path, {"r.csv": dict(notebook="02", commit=second)}, deps)["r.csv"]


def test_a_run_from_uncommitted_code_is_current_once_that_code_is_committed(tmp_path):
    _git(tmp_path, "init", "-q")
    _commit(tmp_path, "code.py", "x = 1\n")
    deps = {"01": ["code.py"]}
    (tmp_path / "code.py").write_text("x = 2\n")  # the run sees code not committed yet
    run = V.git_state(deps["01"], tmp_path)
    assert run["uncommitted_changes"] is True and run["inputs"] == V.inputs_digest(tmp_path, deps["01"])
    prov = {"r.csv": dict(notebook="01", **run)}
    assert "uncommitted changes" in V.stale_results(tmp_path, prov, deps)["r.csv"]
    _commit(tmp_path, "code.py", "x = 2\n")  # committed with its results: current
    assert V.stale_results(tmp_path, prov, deps) == {}
    _commit(tmp_path, "code.py", "x = 3\n")
    assert list(V.stale_results(tmp_path, prov, deps)) == ["r.csv"]


def test_committed_results_are_not_older_than_their_code():
    if subprocess.run(["git", "-C", str(ROOT), "rev-parse", "HEAD"], capture_output=True).returncode:
        pytest.skip("not a git checkout")
    path = ROOT / V.display_path(V.PROVENANCE)
    provenance = json.loads(path.read_text()) if path.is_file() else {}
    unrecorded = V.unrecorded_notebooks(provenance)
    if unrecorded:
        warnings.warn(f"no provenance for the results of notebooks {', '.join(unrecorded)} (run `make reproduce` "
                      f"to record them in {V.display_path(V.PROVENANCE)}); their staleness is not checked",
                      UserWarning)
    recorded = {e["notebook"] for e in provenance.values()} & set(V.OUTPUTS)
    dependencies = {n: V.notebook_dependencies(n) for n in recorded}
    stale = V.stale_results(ROOT, provenance, dependencies)
    assert not stale, "results older than their code (run `make reproduce ONLY=NN`):\n" + "\n".join(
        f"{k}: {v}" for k, v in stale.items())


# ---------------------------------------------------------------- a real run, twice


def _fast_run(out):
    env = dict(os.environ, MAVAC_CACHE=str(out / "cache"))  # each run computes everything itself
    row = V.run_notebook("01", out, out / "executed", env=env)
    return V.record_run(row, out, out / "executed", env=env, fast=True)


def test_fast_notebook_gives_identical_files_twice_beside_a_cpu_hog(tmp_path, monkeypatch):
    monkeypatch.setenv("MAVAC_FAST", "1")
    monkeypatch.setenv("OMP_NUM_THREADS", "1")
    written = _fast_run(tmp_path / "a")
    hog = subprocess.Popen([sys.executable, "-c", "while True: pass"])
    try:
        _fast_run(tmp_path / "b")
    finally:
        hog.kill()
        hog.wait()
    assert written == ["build/results/ik_accuracy.csv", "build/results/machines.csv", "build/results/parts.csv"]
    outcomes = V.verify(tmp_path / "a", tmp_path / "b", fast=True)
    assert [o.line() for o in outcomes if o.status != "identical"] == []
    assert len(outcomes) == 4  # the three CSVs and reproduce_times.csv
    provenance = json.loads((tmp_path / "a" / "build" / "results" / "provenance.json").read_text())
    assert sorted(provenance) == written
    assert {e["notebook"] for e in provenance.values()} == {"01"} and provenance[written[0]]["MAVAC_FAST"] == "1"
