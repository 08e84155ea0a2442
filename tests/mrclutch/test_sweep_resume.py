"""Resume: every chunk recorded in the ``.meta.json`` (rows, bytes, SHA-256) is verified, a
damaged one is refused by its index and ``repair`` recomputes just it; a CSV and a Parquet
dataset of one part a chunk both carry on to exactly the bytes of an uninterrupted run."""

import hashlib
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from test_sweep_engine import OUTPUTS, InterruptAfter, geometric_outputs, grid_spec

from geometry import ParameterError
from mrclutch.sweep import ParamRange, SweepSpec, output_lock, run_sweep

pq = pytest.importorskip("pyarrow.parquet")


def big_spec(chunk=50):
    """≈ 10⁴ rows (≈ 0.4 MB of CSV) in 216 chunks."""
    return SweepSpec(
        (
            ParamRange("gap", 0.2e-3, 0.5e-3, 40),
            ParamRange("n_drums", 1, 3, 0),
            ParamRange("drum_thickness", 0.1e-3, 0.4e-3, 90),
        ),
        chunk_size=chunk,
    )


def _meta(out):
    return json.loads(out.with_name(out.name + ".meta.json").read_text())


def test_every_chunk_is_recorded_with_its_rows_bytes_and_checksum(tmp_path):
    spec = grid_spec(chunk=5)  # 36 designs: 8 chunks, the last holds 1
    out = tmp_path / "a.csv"
    run_sweep(spec, out, geometric_outputs, OUTPUTS, progress=False)
    data = out.read_bytes()
    header = data.index(b"\n") + 1
    chunks = _meta(out)["chunks"]
    assert [c["rows"] for c in chunks] == [[5 * k, min(5 * k + 5, 36)] for k in range(8)]
    assert chunks[0]["offset"] == header
    assert sum(c["bytes"] for c in chunks) == len(data) - header
    for c in chunks:
        piece = data[c["offset"] : c["offset"] + c["bytes"]]
        assert hashlib.sha256(piece).hexdigest() == c["sha256"]
        ids = [int(line.split(b",")[0]) for line in piece.splitlines()]
        assert ids == list(range(*c["rows"]))


def test_csv_resume_cuts_what_follows_the_last_recorded_chunk(tmp_path):
    spec = big_spec()
    whole = tmp_path / "whole.csv"
    run_sweep(spec, whole, geometric_outputs, OUTPUTS, progress=False)
    out = tmp_path / "x.csv"
    part = run_sweep(spec, out, InterruptAfter(2), OUTPUTS, progress=False)
    assert part.rows == 100 and len(_meta(out)["chunks"]) == 2
    lines = whole.read_bytes().split(b"\n")
    with out.open("ab") as f:  # 37 rows of chunk 2 and half a line: written, not recorded
        f.write(b"\n".join(lines[101:138]) + b"\n" + lines[138][:9])
    again = run_sweep(spec, out, geometric_outputs, OUTPUTS, resume=True, progress=False)
    assert again.complete and again.resumed_from == 100
    assert out.read_bytes() == whole.read_bytes()
    assert _meta(out) == _meta(whole)


def test_csv_resume_of_a_finished_file_keeps_the_short_last_chunk(tmp_path):
    spec = grid_spec(chunk=5)  # 36 designs: the last chunk holds 1
    out = tmp_path / "a.csv"
    run_sweep(spec, out, geometric_outputs, OUTPUTS, progress=False)
    before = out.read_bytes()
    again = run_sweep(spec, out, geometric_outputs, OUTPUTS, resume=True, progress=False)
    assert again.complete and again.resumed_from == 36 and out.read_bytes() == before


def _delete_row(data, i):
    lines = data.split(b"\n")
    return b"\n".join(lines[: 1 + i] + lines[2 + i :])


def _duplicate_row(data, i):
    lines = data.split(b"\n")
    return b"\n".join([*lines[: 2 + i], lines[1 + i], *lines[2 + i :]])


def _alter_row(data, i):  # one digit of one row, the file's length unchanged
    lines = data.split(b"\n")
    row = bytearray(lines[1 + i])
    j = row.rindex(b",") + 2
    row[j] = ord("7") if row[j] != ord("7") else ord("3")
    lines[1 + i] = bytes(row)
    return b"\n".join(lines)


def _remove_chunk(data, k, size=5):
    lines = data.split(b"\n")
    return b"\n".join(lines[: 1 + k * size] + lines[1 + (k + 1) * size :])


@pytest.mark.parametrize(
    ("damage", "chunk"),
    [
        (lambda d: _delete_row(d, 12), 2),
        (lambda d: _duplicate_row(d, 17), 3),
        (lambda d: _alter_row(d, 11), 2),
        (lambda d: _remove_chunk(d, 3), 3),
        (lambda d: d[:-10], 7),  # the last recorded chunk (1 row) cut short
        (lambda d: b"design_id,gap_MM" + d[16:], -1),  # another column named in the header
    ],
    ids=["row deleted", "row duplicated", "row altered", "chunk removed", "tail cut", "header"],
)
def test_a_damaged_results_file_is_refused_naming_the_chunk_and_repair_restores_it(
    tmp_path, damage, chunk
):
    spec = grid_spec(chunk=5)
    whole = tmp_path / "whole.csv"
    run_sweep(spec, whole, geometric_outputs, OUTPUTS, progress=False)
    out = tmp_path / "x.csv"
    run_sweep(spec, out, InterruptAfter(8), OUTPUTS, progress=False)  # all 8 chunks
    meta_before = _meta(out)
    out.write_bytes(damage(out.read_bytes()))
    what = "its header row" if chunk < 0 else f"chunk {chunk} \\(rows {5 * chunk}–"
    with pytest.raises(ParameterError, match=f"x.csv: {what}.*--repair"):
        run_sweep(spec, out, geometric_outputs, OUTPUTS, resume=True, progress=False)
    evals = []

    def counting(fields):
        evals.append(len(fields["gap"]))
        return geometric_outputs(fields)

    res = run_sweep(spec, out, counting, OUTPUTS, repair=True, progress=False)
    assert res.complete and out.read_bytes() == whole.read_bytes()
    assert _meta(out) == meta_before == _meta(whole)
    if chunk >= 0:
        assert res.repaired == (chunk,) and len(evals) == 1  # just the damaged chunk
    else:
        assert res.repaired == () and evals == []  # the header alone is rewritten


def test_repair_refuses_a_chunk_that_recomputes_differently(tmp_path):
    spec = grid_spec(chunk=5)
    out = tmp_path / "x.csv"
    run_sweep(spec, out, geometric_outputs, OUTPUTS, progress=False)
    out.write_bytes(_alter_row(out.read_bytes(), 3))

    def other(fields):
        res = geometric_outputs(fields)
        return {k: v * 2 for k, v in res.items()}

    with pytest.raises(ParameterError, match="chunk 0 recomputed does not match"):
        run_sweep(spec, out, other, OUTPUTS, repair=True, progress=False)


@pytest.mark.parametrize(
    ("edit", "fragment"),
    [
        (lambda m: m.unlink(), "meta.json: missing; cannot verify"),
        (
            lambda m: m.write_text(
                json.dumps({k: v for k, v in json.loads(m.read_text()).items() if k != "chunks"})
            ),
            "records no chunk checksums",
        ),
        (
            lambda m: m.write_text(m.read_text().replace('"rows": [5, 10]', '"rows": [5, 11]')),
            "its chunk records are damaged",
        ),
        (lambda m: m.write_text("{"), "unreadable"),
    ],
    ids=["missing", "legacy", "damaged", "unreadable"],
)
def test_resume_refuses_without_a_sound_record(tmp_path, edit, fragment):
    spec = grid_spec(chunk=5)
    out = tmp_path / "x.csv"
    run_sweep(spec, out, InterruptAfter(3), OUTPUTS, progress=False)
    edit(out.with_name("x.csv.meta.json"))
    with pytest.raises(ParameterError, match=fragment):
        run_sweep(spec, out, geometric_outputs, OUTPUTS, resume=True, progress=False)


def _columns(path):
    table = pq.read_table(path)
    return table.column_names, {n: table[n].to_numpy() for n in table.column_names}


def test_parquet_interrupted_then_resumed_equals_uninterrupted_and_the_csv(tmp_path):
    spec = grid_spec(chunk=5)
    a, b = tmp_path / "a.parquet", tmp_path / "b.parquet"
    whole = run_sweep(spec, a, geometric_outputs, OUTPUTS, progress=False)
    assert whole.complete and sorted(p.name for p in a.iterdir())[0] == "part-000000.parquet"
    part = run_sweep(spec, b, InterruptAfter(3), OUTPUTS, progress=False)
    assert not part.complete and part.rows == 15
    assert pq.read_table(b).num_rows == 15  # what an interruption keeps is readable
    (b / ".part-000003.parquet.tmp").write_bytes(b"PAR1 half a part")  # killed mid-write
    again = run_sweep(spec, b, geometric_outputs, OUTPUTS, resume=True, progress=False)
    assert again.complete and again.resumed_from == 15
    assert sorted(p.name for p in b.iterdir()) == sorted(p.name for p in a.iterdir())
    for p in a.iterdir():  # byte for byte
        assert (b / p.name).read_bytes() == p.read_bytes()
    names, cols = _columns(b)
    assert np.array_equal(cols["design_id"], np.arange(spec.n_designs))
    run_sweep(spec, tmp_path / "c.csv", geometric_outputs, OUTPUTS, progress=False)
    csv = np.genfromtxt(tmp_path / "c.csv", delimiter=",", names=True)
    assert list(csv.dtype.names) == names
    for n in names:
        np.testing.assert_allclose(cols[n], csv[n], rtol=1e-8)  # CSV keeps 9 digits
    schema = pq.read_schema(a / "part-000001.parquet")
    assert schema.field("gap_mm").metadata == {
        b"unit": b"mm",
        b"description": b"swept DrumClutch.gap",
    }
    assert str(schema.field("n_drums").type) == "int64"
    meta = json.loads(schema.metadata[b"mrclutch.sweep"])
    sidecar = _meta(tmp_path / "a.parquet")
    assert meta == {k: v for k, v in sidecar.items() if k != "chunks"}
    for c in sidecar["chunks"]:  # each part's size and checksum as written
        data = (a / c["part"]).read_bytes()
        assert len(data) == c["bytes"] and hashlib.sha256(data).hexdigest() == c["sha256"]


@pytest.mark.parametrize(
    ("damage", "fragment"),
    [
        (lambda p: p.unlink(), r"chunk 1 \(rows 5–9\) \(part-000001\.parquet\) is missing"),
        (lambda p: p.write_bytes(p.read_bytes()[:-100]), r"chunk 1 .*holds \d+ bytes, not the"),
        (
            lambda p: p.write_bytes(p.read_bytes()[:200] + b"X" + p.read_bytes()[201:]),
            r"chunk 1 .*does not match its checksum",
        ),
    ],
    ids=["removed", "truncated", "altered"],
)
def test_parquet_damaged_part_is_refused_and_repair_restores_it(tmp_path, damage, fragment):
    spec = grid_spec(chunk=5)
    whole, out = tmp_path / "a.parquet", tmp_path / "r.parquet"
    run_sweep(spec, whole, geometric_outputs, OUTPUTS, progress=False)
    run_sweep(spec, out, InterruptAfter(4), OUTPUTS, progress=False)
    damage(out / "part-000001.parquet")
    with pytest.raises(ParameterError, match=fragment + ".*--repair"):
        run_sweep(spec, out, geometric_outputs, OUTPUTS, resume=True, progress=False)
    res = run_sweep(spec, out, geometric_outputs, OUTPUTS, repair=True, progress=False)
    assert res.complete and res.repaired == (1,) and res.resumed_from == 20
    assert sorted(p.name for p in out.iterdir()) == sorted(p.name for p in whole.iterdir())
    for p in whole.iterdir():
        assert (out / p.name).read_bytes() == p.read_bytes()
    assert pq.read_table(out).num_rows == spec.n_designs


def test_parquet_overwrite_spares_foreign_files(tmp_path):
    spec = grid_spec(chunk=5)
    out = tmp_path / "r.parquet"
    run_sweep(spec, out, InterruptAfter(4), OUTPUTS, progress=False)
    (out / "notes.txt").write_text("mine")
    with pytest.raises(ParameterError, match=r"holds notes\.txt, not a sweep's part; not replaced"):
        run_sweep(spec, out, geometric_outputs, OUTPUTS, overwrite=True, progress=False)


# ---- one writer at a time ----------------------------------------------------------------


def test_a_second_writer_is_refused_while_the_first_holds_the_output(tmp_path):
    spec = grid_spec(chunk=5)
    out = tmp_path / "x.csv"
    with output_lock(out) as lock:
        assert lock.read_text() == f"{os.getpid()}\n"
        for kw in ({"overwrite": True}, {"resume": True}, {"repair": True}):
            with pytest.raises(ParameterError, match=rf"x\.csv: another sweep \(pid "
                               rf"{os.getpid()}\) is writing it"):  # fmt: skip
                run_sweep(spec, out, geometric_outputs, OUTPUTS, progress=False, **kw)
        assert not out.exists()
    res = run_sweep(spec, out, geometric_outputs, OUTPUTS, progress=False)
    assert res.complete and not lock.exists()


def test_the_lock_of_a_killed_writer_is_taken_over(tmp_path):
    spec = grid_spec(chunk=5)
    out = tmp_path / "k.parquet"
    code = ("import sys, time\nfrom mrclutch.sweep import output_lock\n"
            "with output_lock(sys.argv[1]):\n    print('locked', flush=True)\n"
            "    time.sleep(120)\n")  # fmt: skip
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[2])}
    child = subprocess.Popen([sys.executable, "-c", code, str(out)], stdout=subprocess.PIPE,
                             env=env)  # fmt: skip
    try:
        assert child.stdout.readline() == b"locked\n"
        with pytest.raises(ParameterError, match=rf"another sweep \(pid {child.pid}\)"):
            run_sweep(spec, out, geometric_outputs, OUTPUTS, progress=False)
    finally:
        child.kill()  # SIGKILL: no clean-up runs in the child
        child.wait()
        child.stdout.close()
    lock = tmp_path / "k.parquet.lock"
    assert lock.read_text() == f"{child.pid}\n"  # left behind by the dead writer
    res = run_sweep(spec, out, geometric_outputs, OUTPUTS, progress=False)
    assert res.complete and res.rows == spec.n_designs and not lock.exists()
