"""A sweep's empty cells carry their reason in the meta file (issue 44 item 4): every
column that holds a NaN/inf cell on a small grid says in its description what an empty or
infinite cell means (the meta's JSON itself has no null the walker of
tests/mrclutch/test_json_walk.py does not explain)."""

from __future__ import annotations

import csv
import json
import math

from test_json_walk import unexplained

from mrclutch.cli.main import main

#: 3 gaps (0.1, 1.05, 2 mm) x drum counts 1 to 20: the 20-drum stacks' levers are
#: overdamped (no resonance: NaN).
SPEC = ('[sweep]\nmode = "grid"\n[parameters]\ngap_mm = {min = 0.1, max = 2, count = 3}\n'
        "n_drums = {min = 1, max = 20, count = 2}\n")  # fmt: skip


def test_every_column_with_an_empty_cell_says_why(tmp_path, capsys):
    spec = tmp_path / "s.toml"
    spec.write_text(SPEC)
    out = tmp_path / "r.csv"
    assert main(["sweep", str(spec), "--out", str(out), "--no-progress"]) == 0
    capsys.readouterr()
    meta = json.loads((tmp_path / "r.csv.meta.json").read_text())
    assert unexplained(meta) == []
    with out.open() as f:
        rows = list(csv.DictReader(f))
    assert {r["n_drums"] for r in rows} >= {"1", "20"}
    empty = set()
    for r in rows:
        for k, v in r.items():
            try:
                x = float(v) if v != "" else math.nan
            except ValueError:
                continue
            if not math.isfinite(x) and r["valid"] == "1":
                empty.add(k)
    assert "resonance_hz" in empty  # the overdamped stacks: what the check is for
    cols = meta["columns"]
    unsaid = [k for k in sorted(empty)
              if not any(w in cols[k]["description"] for w in ("NaN", "empty", "inf"))]  # fmt: skip
    assert unsaid == []
    assert "overdamped" in cols["resonance_hz"]["description"]
