import pandas as pd
import pytest

from mavac.paper import compare, paper_scalar, paper_table, paper_values


def test_every_row_cites_a_table_or_section():
    df = paper_values()
    assert set(df["paper"]) == {"mavac", "kabir"}
    assert (df["ref"].str.len() > 0).all() and (df["unit"].str.len() > 0).all()
    assert pd.to_numeric(df["value"], errors="coerce").notna().all()


def test_table1_is_wide_and_in_fractions():
    t1 = paper_table("mavac", "Table 1")
    assert list(t1.columns) == ["P_s", "spots", "C", "O"]
    assert t1["C"].between(0, 1).all() and len(t1) == 7


def test_scalar_and_errors():
    assert 0 < paper_scalar("mavac", "Fig. 6", "C_per_guard") < 1
    with pytest.raises(ValueError, match="ref='Table 99'"):
        paper_values(ref="Table 99")
    with pytest.raises(ValueError, match="no single value"):
        paper_scalar("kabir", "Table II", "setups")


def test_compare_side_by_side():
    paper = paper_table("kabir", "Table II")
    ours = pd.DataFrame({"object": ["sine", "extra"], "setups": [7, 1]})
    out = compare(ours, paper, on=["object"], quantities=["setups"])
    assert list(out.columns) == ["object", "setups_paper", "setups_ours"]
    assert out.set_index("object").loc["sine", "setups_ours"] == 7
    assert out.set_index("object").loc["extra", "setups_paper"] != out.set_index("object").loc["extra", "setups_paper"]
