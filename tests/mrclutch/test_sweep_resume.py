"""Resume from the end of the file: a CSV's tail only (never the whole file), and a Parquet
dataset of one part a chunk; both carry on to exactly the rows of an uninterrupted run."""

import io
import json

import numpy as np
import pytest
from test_sweep_engine import OUTPUTS, InterruptAfter, geometric_outputs, grid_spec

from geometry import ParameterError
from mrclutch.sweep import ParamRange, SweepSpec, _CsvSink, run_sweep

pq = pytest.importorskip("pyarrow.parquet")


def big_spec(chunk=50):
    """≈ 10⁴ rows (≈ 0.4 MB of CSV): much more than the tail a resume may read."""
    return SweepSpec(
        (
            ParamRange("gap", 0.2e-3, 0.5e-3, 40),
            ParamRange("n_drums", 1, 3, 0),
            ParamRange("drum_thickness", 0.1e-3, 0.4e-3, 90),
        ),
        chunk_size=chunk,
    )


class CountingFile(io.BytesIO):
    def __init__(self, data):
        super().__init__(data)
        self.read_bytes = 0

    def read(self, n=-1):
        out = super().read(n)
        self.read_bytes += len(out)
        return out

    def readline(self, n=-1):
        out = super().readline(n)
        self.read_bytes += len(out)
        return out


def test_csv_resume_reads_only_the_tail_and_cuts_a_partial_chunk(tmp_path):
    spec = big_spec()
    whole = tmp_path / "whole.csv"
    run_sweep(spec, whole, geometric_outputs, OUTPUTS, progress=False)
    text = whole.read_bytes()
    lines = text.split(b"\n")
    # 137 complete rows (2 whole chunks of 50 + 37) and half of the next line
    kept = b"\n".join(lines[: 1 + 137]) + b"\n" + lines[138][:9]
    sink = _CsvSink(tmp_path / "x.csv", spec, lines[0].decode().split(","))
    f = CountingFile(kept)
    assert sink._trim(f) == 100
    assert f.getvalue() == b"\n".join(lines[:101]) + b"\n"
    assert f.read_bytes < 64 * 1024 + 2 * len(lines[0]) < len(text) / 4

    big = b"\n".join(lines[: 1 + 9950]) + b"\n"  # 199 whole chunks and no partial line
    f = CountingFile(big)
    assert sink._trim(f) == 9950 and f.getvalue() == big
    assert f.read_bytes < len(big) / 4


def test_csv_resume_of_a_finished_file_keeps_the_short_last_chunk(tmp_path):
    spec = grid_spec(chunk=5)  # 36 designs: the last chunk holds 1
    out = tmp_path / "a.csv"
    run_sweep(spec, out, geometric_outputs, OUTPUTS, progress=False)
    before = out.read_bytes()
    again = run_sweep(spec, out, geometric_outputs, OUTPUTS, resume=True, progress=False)
    assert again.complete and again.resumed_from == 36 and out.read_bytes() == before


@pytest.mark.parametrize(
    ("tail", "fragment"),
    [
        (b"junk,row\n", "its last row b'junk,row' is not a row of this sweep"),
        (b"999,1,2,3,4,5\n", "is not a row of this sweep"),  # beyond the spec's 36 designs
    ],
)
def test_csv_resume_refuses_a_foreign_last_row(tmp_path, tail, fragment):
    spec = grid_spec(chunk=5)
    out = tmp_path / "b.csv"
    run_sweep(spec, out, InterruptAfter(2), OUTPUTS, progress=False)
    with out.open("ab") as f:
        f.write(tail)
    with pytest.raises(ParameterError, match=fragment):
        run_sweep(spec, out, geometric_outputs, OUTPUTS, resume=True, progress=False)


def test_csv_resume_refuses_rows_out_of_sequence(tmp_path):
    spec = grid_spec(chunk=5)
    out = tmp_path / "b.csv"
    run_sweep(spec, out, InterruptAfter(3), OUTPUTS, progress=False)  # rows 0..14
    with out.open("a") as f:  # rows 15, 17, 18 of the partial chunk: row 16 lost
        f.write("15,1,1,1,1,1\n17,1,1,1,1,1\n18,1,1,1,1,1\n")
    with pytest.raises(ParameterError, match="row 16 reads b'15,1,1,1,1,1'"):
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
    assert meta == json.loads((tmp_path / "a.parquet.meta.json").read_text())


def test_parquet_resume_refuses_a_missing_part_and_overwrite_spares_foreign_files(tmp_path):
    spec = grid_spec(chunk=5)
    out = tmp_path / "r.parquet"
    run_sweep(spec, out, InterruptAfter(4), OUTPUTS, progress=False)
    (out / "part-000001.parquet").unlink()
    with pytest.raises(ParameterError, match=r"part-000001\.parquet is missing or out of place"):
        run_sweep(spec, out, geometric_outputs, OUTPUTS, resume=True, progress=False)
    (out / "part-000003.parquet").write_bytes(b"not parquet")
    (out / "part-000001.parquet").write_bytes(b"")
    with pytest.raises(ParameterError, match=r"part-000003\.parquet: unreadable"):
        run_sweep(spec, out, geometric_outputs, OUTPUTS, resume=True, progress=False)
    (out / "notes.txt").write_text("mine")
    with pytest.raises(ParameterError, match=r"holds notes\.txt, not a sweep's part; not replaced"):
        run_sweep(spec, out, geometric_outputs, OUTPUTS, overwrite=True, progress=False)
    (out / "notes.txt").unlink()
    res = run_sweep(spec, out, geometric_outputs, OUTPUTS, overwrite=True, progress=False)
    assert res.complete and pq.read_table(out).num_rows == spec.n_designs
