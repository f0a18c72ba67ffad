"""The paper's study reports say what they show: figure captions name scheme, dt and law; runs
not at rest are left out and named; the paper's statements are checked against the runs' own
numbers; discharge tables never print a spread for one member and picture the median member."""
from pathlib import Path

import numpy as np
import pytest

from dem.compare.figures import runs as figures
from dem.compare.papers import paper_claims, paper_discharge, paper_static

REPO = Path(__file__).resolve().parents[2]


def contacts(ny, f, e_s=None):
    ny = np.asarray(ny, float)
    nx = np.sqrt(1 - ny * ny)
    e_s = np.zeros(len(ny)) if e_s is None else np.asarray(e_s, float)
    return {"kind": np.array(["dd"] * len(ny) + ["dw"]), "nx": np.append(nx, 0.0), "ny": np.append(ny, 1.0),
            "e_n": np.append(np.asarray(f, float), 1e9), "e_s": np.append(e_s, 0.0)}


def test_verticality_weighs_disc_contact_forces():
    assert paper_claims.verticality(contacts([0, 0], [1, 5])) == 0.0          # horizontal chains
    assert paper_claims.verticality(contacts([1, -1], [1, 5])) == 1.0         # vertical (either sense)
    assert paper_claims.verticality(contacts([0, 1], [1, 3])) == pytest.approx(0.75)   # the wall contact is not counted


def test_verticality_measures_the_forces_not_the_lattice():
    """The same normals (one lattice) with shear forces give another verticality: a horizontal
    normal carrying shear e_s = e_n has its resultant at 45 degrees."""
    assert paper_claims.verticality(contacts([0, 0], [1, 1], e_s=[1, 1])) == pytest.approx(0.5)
    assert paper_claims.verticality(contacts([0.6, 0.6], [1, 1], e_s=[0.3, 0.3])) != \
        pytest.approx(paper_claims.verticality(contacts([0.6, 0.6], [1, 1])))


def test_peaks_are_judged_at_both_samplings():
    def ens(raw, win):
        return {"pattern": {"piping": 8}, "peak_ratio_bottom": {"mean": raw}, "peak_ratio_bottom_windowed": {"mean": win}}
    row = [r for r in paper_claims.discharge({"11/12": ens(8.31, 2.69)}) if "slit ends" in r["statement"]][0]
    assert not row["agrees"] and row["judged"] == "at 50 ms average only" and "8.31" in row["shows"] and "2.69" in row["shows"]
    assert "| at 50 ms average only |" in paper_claims.table([row])[2]
    both = [r for r in paper_claims.discharge({"11/12": ens(2.5, 2.2)}) if "slit ends" in r["statement"]][0]
    assert both["agrees"] and paper_claims.table([both])[2].endswith("| yes |")
    none = [r for r in paper_claims.discharge({"11/12": ens(9, 4)}) if "slit ends" in r["statement"]][0]
    assert paper_claims.table([none])[2].endswith("| **no** |")


def test_side_force_claim_follows_the_numbers():
    down = [{"arrangement": a, "side_mean": v} for a, v in (("11/12", 9.0), ("14/15", 5.0), ("18/19", 2.0))]
    up = [{"arrangement": a, "side_mean": v} for a, v in (("11/12", 2.0), ("14/15", 5.0), ("18/19", 9.0))]
    assert paper_claims.side_force(down)["agrees"] and "falls at every step" in paper_claims.side_force(down)["shows"]
    assert not paper_claims.side_force(up)["agrees"]
    lines = paper_claims.table([paper_claims.side_force(up)])
    assert lines[0].startswith("| statement | the paper says | these runs show | agrees?") and "**no**" in lines[2]


def test_captions_name_scheme_dt_and_law():
    paper = {"scene": {"name": "silo"}, "options": {"scheme": "paper_eq19", "dt": 1e-4, **figures.PAPER_LAW}}
    shared = {"scene": {"name": "silo"}, "options": {"scheme": "velocity_verlet", "dt": 5e-5, **figures.SHARED_LAW}}
    capped = {"scene": {"name": "silo"}, "options": {**paper["options"], "friction_cap": "total"}}
    assert figures.run_caption(paper) == "silo, paper_eq19, dt = 0.0001 s, the paper's law"
    assert figures.run_caption(shared).endswith("the shared law (LIGGGHTS, YADE)")
    assert figures.run_caption(capped).endswith("law: friction_cap total")
    assert figures.common_caption([paper, paper]) == "paper_eq19, dt = 0.0001 s, the paper's law"
    assert figures.common_caption([paper, shared]) == "mixed scheme, mixed dt, mixed law"


def test_one_member_has_no_spread_and_the_median_member_is_pictured():
    assert "±" not in paper_discharge.fmt({"n": 1, "mean": 44.0, "stderr": 0.0})
    assert paper_discharge.fmt({"n": 3, "mean": 44.0, "stderr": 2.0}) == "44 ± 2"
    ens = {"runs": [{"member": 0, "discs_out_at_1s": 90}, {"member": 1, "discs_out_at_1s": 12},
                    {"member": 2, "discs_out_at_1s": 70}, {"member": 3, "discs_out_at_1s": None}]}
    assert paper_discharge.median_member(ens)["member"] == 2
    assert paper_discharge.median_member({"runs": []}) is None


def test_static_report_leaves_out_runs_not_at_rest_and_checks_the_paper(tmp_path, dem_binary):
    records = [paper_static.run_one(dem_binary, s, "paper_eq19", 1e-4, tmp_path) for s in (12, 18)]
    assert all(r["status"] == "rest" for r in records)
    records.append({**records[1], "s": 19, "arrangement": "18/19", "rest": False, "status": "end_time"})
    paper_static.write_report(tmp_path, records, dem_binary)
    text = (tmp_path / "report.md").read_text()
    checks = text[text.index("## Checks at rest"):text.index("## Pictures")]
    assert "| 11/12 |" in checks and "| 17/18 |" in checks and "| 18/19 |" not in checks
    assert "paper_eq19 0.0001 18/19 (no rest by end time)" in checks
    claims = text[text.index("## The paper's statements"):]
    assert "2 of 8 arrangements at rest" in claims
    # 11/12's chains are the more horizontal, its side-wall force the larger (the engine's numbers)
    assert "| force chains | most horizontal in 11/12, most vertical in 18/19 |" in claims
    row = next(line for line in claims.splitlines() if line.startswith("| force chains"))
    v = {k: float(x) for k, x in (p.split() for p in row.split("|")[3].split(":")[1].split("(")[0].split(","))}
    assert v["11/12"] < v["17/18"]


def test_discharge_claims_follow_the_ensembles():
    def ens(funnel, piping, bottom, side):
        return {"pattern": {"funnel": funnel, "piping": piping, "undetermined": 0},
                "peak_ratio_bottom": {"mean": bottom}, "peak_ratio_bottom_windowed": {"mean": bottom * 0.9},
                "peak_ratio_side": {"mean": side}, "peak_ratio_side_windowed": {"mean": side * 0.9}}
    rows = {r["statement"]: r for r in paper_claims.discharge({"17/18": ens(7, 1, 11.0, 4.0),
                                                              "11/12": ens(0, 8, 2.5, 1.0)})}
    assert all(r["agrees"] for r in rows.values()) and len(rows) == 5
    rows = {r["statement"]: r for r in paper_claims.discharge({"17/18": ens(1, 7, 40.0, 30.0),
                                                              "11/12": ens(8, 0, 9.0, 1.0)})}
    assert not any(r["agrees"] for r in rows.values())
    assert "funnel 1, piping 7, undetermined 0 of 8 members" in rows["17/18 flow pattern"]["shows"]
