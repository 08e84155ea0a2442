"""Issue 45: a resume knows every input of its rows. The ``.meta.json`` fingerprint covers
the whole spec (each section), the contents of the material files it names and the model's
version; a resume on a changed input is refused in one line naming what changed. A section
the sweep cannot use is refused, never ignored; a chunk the evaluator refuses leaves no
header-only file."""

import json

import pytest
from test_sweep_engine import InterruptAfter, geometric_outputs

from geometry import ParameterError
from geometry.materials import SLOTS
from geometry.params import preset
from mrclutch.sweep import load_spec, read_results, run_sweep
from mrclutch.sweep import record as sweep_record
from mrclutch.sweep import spec as sweep_spec

OUTPUTS = ("outer_radius", "pole_radius")

#: One spec with every section a sweep spec takes (each changed in turn below).
SECTIONS = {
    "sweep": 'mode = "grid"\nbase = "paper"\nchunk_size = 2',
    "parameters": "gap_mm = {min = 0.3, max = 0.6, count = 4}\nn_drums = {min = 1, max = 2}",
    "clutch": "drum_thickness_mm = 0.3",
    "operating": "max_current_A = 6.0",
    "transmission": "lever_mm = 170",
    "support": "bearings = 2",
    "amplifier": "supply_voltage_V = 24.0",
    "laminations": "core_mm = 0.5",
    "uncertainty": "viscosity_spread_pct = 10",
    "materials": 'fluid_file = "fluid.toml"',
    "duty": "torque_N_m = 0.2\ntime_s = 60",
    "render": 'rule = "K_max"',
}

#: A changed value in each section (the rows it writes change with it).
CHANGED = {
    "sweep": 'mode = "grid"\nbase = "paper"\nchunk_size = 2\nseed = 3',
    "parameters": "gap_mm = {min = 0.3, max = 0.7, count = 4}\nn_drums = {min = 1, max = 2}",
    "clutch": "drum_thickness_mm = 0.35",
    "operating": "max_current_A = 5.0",
    "transmission": "lever_mm = 150",
    "support": "bearings = 1",
    "amplifier": "supply_voltage_V = 12.0",
    "laminations": "core_mm = 0.3",
    "uncertainty": "viscosity_spread_pct = 20",
    "materials": 'fluid_file = "other.toml"',
    "duty": "torque_N_m = 0.2\ntime_s = 90",
    "render": "",  # the one other `[render]` a sweep takes: the same rule, implied
}

FLUID = """name = "{name}"
label = "test fluid"
density = 3000.0
specific_heat = 800.0
thermal_conductivity = 0.6
phi = 0.3
carrier_c = 1.0
viscosity = {viscosity}
viscosity_temperature = 40.0
carrier_points = [[40.0, 19e-6], [100.0, 4.1e-6]]
temperature_range = [-40.0, 130.0]
[bh]
b = [0.1, 0.5, 0.9]
h = [1e4, 8e4, 2.5e5]
"""


@pytest.fixture(autouse=True)
def _registry():
    """The materials registry left as found: the fluids these tests load are theirs alone
    (another file's test lists the known fluids; the registry has no removal)."""
    import geometry.materials as geo
    import magnetics.materials as mag

    tables = (geo._RECORDS, geo._DENSITY, geo._LABEL, geo._COLOUR, geo._KIND, mag._MATERIALS,
              mag._FLUIDS, sweep_spec._LOADED)  # fmt: skip
    saved = [dict(t) for t in tables]
    yield
    for t, copy in zip(tables, saved, strict=True):
        t.clear()
        t.update(copy)


def write_spec(folder, sections, extra=""):
    text = "\n".join(f"[{k}]\n{v}\n" for k, v in sections.items()) + extra
    (folder / "spec.toml").write_text(text)
    return folder / "spec.toml"


def fluid_files(folder, viscosity=0.1):
    (folder / "fluid.toml").write_text(FLUID.format(name="inputs_fluid", viscosity=viscosity))
    (folder / "other.toml").write_text(FLUID.format(name="inputs_other", viscosity=0.1))


def dims_only(evaluate):
    """``evaluate`` (of dimensions only) on a batch that may carry material columns."""
    return lambda fields: evaluate({k: v for k, v in fields.items() if k not in SLOTS})


def interrupted(folder, sections):
    """A sweep of the spec stopped after two of its four chunks."""
    spec, _ = load_spec(write_spec(folder, sections))
    res = run_sweep(spec, folder / "r.csv", dims_only(InterruptAfter(2)), OUTPUTS,
                    progress=False)  # fmt: skip
    assert not res.complete and res.rows == 4
    return spec


def test_every_section_of_the_spec_is_in_the_record(tmp_path):
    """Every table of the spec file has its digest in the record, whatever its name (the
    record does not list the sections it knows: a section added later is covered too),
    with the fluid file [materials] names."""
    fluid_files(tmp_path)
    interrupted(tmp_path, SECTIONS)
    meta = json.loads((tmp_path / "r.csv.meta.json").read_text())
    assert set(meta["inputs"]) == {f"[{k}]" for k in SECTIONS} | {"material file fluid.toml"}
    assert all(len(v) == 64 for v in meta["inputs"].values())  # SHA-256 hex digests


@pytest.mark.parametrize("section", sorted(SECTIONS))
def test_a_resume_after_any_section_changed_is_refused_naming_it(tmp_path, section):
    """Cut after two chunks, then one section changed: resuming would mix two inputs' rows
    in one file; it is refused in one line that names the section. Unchanged, it resumes
    to the rows of an uninterrupted run."""
    fluid_files(tmp_path)
    interrupted(tmp_path, SECTIONS)
    before = (tmp_path / "r.csv").read_bytes()
    spec, _ = load_spec(write_spec(tmp_path, {**SECTIONS, section: CHANGED[section]}))
    with pytest.raises(ParameterError) as err:
        run_sweep(spec, tmp_path / "r.csv", geometric_outputs, OUTPUTS, resume=True,
                  progress=False)  # fmt: skip
    msg = str(err.value)
    assert f"[{section}] changed" in msg and "cannot resume" in msg and "\n" not in msg
    # the only change named (with [materials], the fluid file it names changes too)
    named = msg.split(" model (", 1)[1].split("); cannot", 1)[0].split("; ")
    files = ["material file fluid.toml removed", "material file other.toml added"]
    assert named == [f"[{section}] changed", *(files if section == "materials" else [])]
    assert (tmp_path / "r.csv").read_bytes() == before  # refused: nothing touched
    spec, _ = load_spec(write_spec(tmp_path, SECTIONS))
    again = run_sweep(spec, tmp_path / "r.csv", geometric_outputs, OUTPUTS, resume=True,
                      progress=False)  # fmt: skip
    assert again.complete and again.resumed_from == 4 and again.rows == 8


@pytest.mark.parametrize(("was", "now"), [("MRF-132DG", "MRF-140CG"), ("MRF-140CG", None)])
def test_a_resume_after_the_library_fluid_changed_is_refused(tmp_path, was, now):
    """The issue's case: ``[materials] fluid`` changed (or removed: the base preset's fluid)
    between a cut sweep and its resume would give rows of two fluids in one file."""
    sections = {k: SECTIONS[k] for k in ("sweep", "parameters")}
    interrupted(tmp_path, {**sections, "materials": f'fluid = "{was}"'})
    before = (tmp_path / "r.csv").read_bytes()
    changed = {**sections, "materials": f'fluid = "{now}"'} if now else sections
    spec, _ = load_spec(write_spec(tmp_path, changed))
    what = "changed" if now else "removed"
    with pytest.raises(ParameterError, match=rf"model \(\[materials\] {what}\); cannot resume"):
        run_sweep(spec, tmp_path / "r.csv", geometric_outputs, OUTPUTS, resume=True,
                  progress=False)  # fmt: skip
    assert (tmp_path / "r.csv").read_bytes() == before


def test_a_material_files_contents_are_in_the_record(tmp_path):
    """The spec is unchanged, the fluid file it names is edited (its viscosity): refused,
    naming the file; a comment-free copy with the same bytes resumes."""
    fluid_files(tmp_path)
    interrupted(tmp_path, SECTIONS)
    fluid_files(tmp_path, viscosity=0.2)
    spec, _ = load_spec(write_spec(tmp_path, SECTIONS))
    with pytest.raises(ParameterError, match=r"\(material file fluid.toml changed\); cannot "
                       "resume; pass --overwrite"):  # fmt: skip
        run_sweep(spec, tmp_path / "r.csv", geometric_outputs, OUTPUTS, resume=True,
                  progress=False)  # fmt: skip
    fluid_files(tmp_path)
    spec, _ = load_spec(write_spec(tmp_path, SECTIONS))
    assert run_sweep(spec, tmp_path / "r.csv", geometric_outputs, OUTPUTS, resume=True,
                     progress=False).complete  # fmt: skip


def test_a_fluid_axis_file_is_in_the_record(tmp_path):
    """A fluid axis naming a file (``values = ["MRF-122EG", "fluid.toml"]``): the rows hold
    the registry name it loads as, the record its contents."""
    fluid_files(tmp_path)
    sections = {"sweep": 'mode = "grid"\nchunk_size = 2',
                "parameters": 'fluid = {values = ["MRF-122EG", "fluid.toml"]}\n'
                              "gap_mm = {values = [0.3, 0.4, 0.5, 0.6]}"}  # fmt: skip
    spec = interrupted(tmp_path, sections)
    assert spec.params[0].categories == ("mrf_122eg", "inputs_fluid")
    meta = json.loads((tmp_path / "r.csv.meta.json").read_text())
    assert meta["categories"] == {"fluid": ["mrf_122eg", "inputs_fluid"]}
    assert set(meta["inputs"]) == {"[sweep]", "[parameters]", "material file fluid.toml"}
    fluid_files(tmp_path, viscosity=0.3)
    spec, _ = load_spec(write_spec(tmp_path, sections))
    with pytest.raises(ParameterError, match=r"material file fluid\.toml changed"):
        run_sweep(spec, tmp_path / "r.csv", dims_only(geometric_outputs), OUTPUTS, resume=True,
                  progress=False)  # fmt: skip


def test_the_model_version_is_in_the_record(tmp_path, monkeypatch):
    """Rows of another model (mrclutch version or its data files) are not continued."""
    spec = interrupted(tmp_path, {k: SECTIONS[k] for k in ("sweep", "parameters")})
    meta = json.loads((tmp_path / "r.csv.meta.json").read_text())
    assert meta["model"] == sweep_record.model_version()
    assert meta["model"].startswith("mrclutch ") and ", model data " in meta["model"]
    monkeypatch.setattr(sweep_record, "model_version", lambda: "mrclutch 9.9, model data x")
    with pytest.raises(ParameterError, match=r"the model changed \(was mrclutch .*, now "
                       r"mrclutch 9.9, model data x\)"):  # fmt: skip
        run_sweep(spec, tmp_path / "r.csv", geometric_outputs, OUTPUTS, resume=True,
                  progress=False)  # fmt: skip


def test_an_edit_of_the_models_code_is_in_the_record(tmp_path, monkeypatch):
    """The model's version digests its code: a resume across an edit of a model file
    (drag torque ×1.5 in magnetics/drag.py gave rows 2000– of 1.5× the off-state torque in
    the file of rows 0–1999, exit 0, the version number unchanged) is refused. The copy of
    the sources digests as the installed ones; an edit of the command line changes nothing."""
    spec = interrupted(tmp_path, {k: SECTIONS[k] for k in ("sweep", "parameters")})
    copies = {}
    for name in sweep_record.MODEL_PACKAGES:
        for folder in sweep_record._package_folders(name):
            for f in folder.rglob("*.py"):
                copy = tmp_path / "src" / name / f.relative_to(folder)
                copy.parent.mkdir(parents=True, exist_ok=True)
                copy.write_bytes(f.read_bytes())
        copies[name] = [tmp_path / "src" / name]
    installed = sweep_record.code_digest()
    monkeypatch.setattr(sweep_record, "_package_folders", lambda name: copies[name])
    try:
        assert sweep_record.code_digest() == installed
        with (tmp_path / "src/mrclutch/cli/main.py").open("a") as f:
            f.write("\n# the command line computes no row\n")
        assert sweep_record.code_digest() == installed
        with (tmp_path / "src/magnetics/drag.py").open("a") as f:
            f.write("\nDRAG_SCALE = 1.5\n")
        edited = sweep_record.code_digest()
        assert edited != installed
        sweep_record.model_version.cache_clear()
        assert sweep_record.model_version().endswith(f", code {edited[:12]}")
        with pytest.raises(ParameterError, match=rf"the model changed \(was .*, code "
                           rf"{installed[:12]}, now .*, code {edited[:12]}\)"):  # fmt: skip
            run_sweep(spec, tmp_path / "r.csv", geometric_outputs, OUTPUTS, resume=True,
                      progress=False)  # fmt: skip
    finally:
        sweep_record.model_version.cache_clear()


def test_other_outputs_and_an_older_record_are_refused(tmp_path):
    spec = interrupted(tmp_path, {k: SECTIONS[k] for k in ("sweep", "parameters")})
    with pytest.raises(ParameterError, match=r"the output columns differ \(--with\)"):
        run_sweep(spec, tmp_path / "r.csv", geometric_outputs, OUTPUTS[:1], resume=True,
                  progress=False)  # fmt: skip
    mp = tmp_path / "r.csv.meta.json"
    meta = json.loads(mp.read_text())
    del meta["inputs"]
    mp.write_text(json.dumps(meta))
    with pytest.raises(ParameterError, match="names none of the spec's sections"):
        run_sweep(spec, tmp_path / "r.csv", geometric_outputs, OUTPUTS, resume=True,
                  progress=False)  # fmt: skip


def test_top_level_keys_are_in_the_record(tmp_path):
    spec, _ = load_spec(write_spec(tmp_path, {}, 'name = "a"\n' + "\n".join(
        f"[{k}]\n{SECTIONS[k]}" for k in ("sweep", "parameters"))))  # fmt: skip
    run_sweep(spec, tmp_path / "r.csv", InterruptAfter(1), OUTPUTS, progress=False)
    spec, _ = load_spec(write_spec(tmp_path, {}, 'name = "b"\n' + "\n".join(
        f"[{k}]\n{SECTIONS[k]}" for k in ("sweep", "parameters"))))  # fmt: skip
    with pytest.raises(ParameterError, match=r"\(top-level keys changed\)"):
        run_sweep(spec, tmp_path / "r.csv", geometric_outputs, OUTPUTS, resume=True,
                  progress=False)  # fmt: skip


@pytest.mark.parametrize(
    ("table", "body"),
    [("measured", "use_in_model = true\nm1_g = 1.5"), ("measured", "m1_g = 1.5"),
     ("process", "runout_mm = 0.03")],
)  # fmt: skip
def test_a_section_the_sweep_cannot_use_is_refused(tmp_path, table, body):
    """`[measured]` (a bench's figures, of one built device) and `[process]` (the optimiser's
    limits) would be silently ignored by a sweep: refused, naming the table."""
    path = write_spec(tmp_path, {k: SECTIONS[k] for k in ("sweep", "parameters")},
                      f"[{table}]\n{body}\n")  # fmt: skip
    with pytest.raises(ParameterError, match=rf"\[{table}\]: not used by a sweep .*remove it"):
        load_spec(path)


@pytest.mark.parametrize(
    ("body", "fragment"),
    [('rule = "worst_case"', "render.rule = 'worst_case': not used by a sweep"),
     ("K_N_per_m = 50", "render.rule = 'typed': not used by a sweep"),
     ('rule = "typed"\nK_N_per_m = 50', "render.rule = 'typed': not used by a sweep"),
     ('verdict = "nominal"', "render.verdict = 'nominal': not used by a sweep"),
     ('rule = "K_max"\nverdict = "robust"', "render.verdict = 'robust': not used by a sweep"),
     ('rule = "K_max"\nK = 1', r"render\.K: unknown key")],
)  # fmt: skip
def test_a_render_rule_the_rows_do_not_follow_is_refused(tmp_path, body, fragment):
    """A sweep's rows render each design at its own K_max (the K_N_per_m column) and hold no
    verdict: a `[render]` asking another K or a verdict was silently ignored (the rows of
    rule = "typed", K = 50 N/m were byte for byte those without it); refused, naming the
    key."""
    path = write_spec(tmp_path, {k: SECTIONS[k] for k in ("sweep", "parameters")},
                      f"[render]\n{body}\n")  # fmt: skip
    with pytest.raises(ParameterError, match=fragment):
        load_spec(path)


def test_the_render_rule_the_rows_follow_is_taken(tmp_path):
    """``rule = "K_max"`` (or an empty `[render]`) is what the rows do: taken, in the record."""
    for body in ('rule = "K_max"', ""):
        spec, rest = load_spec(write_spec(tmp_path, {k: SECTIONS[k] for k in
                                                     ("sweep", "parameters")},
                                          f"[render]\n{body}\n"))  # fmt: skip
        assert "[render]" in dict(spec.inputs) and "render" in rest


@pytest.mark.parametrize(
    ("table", "fragment"),
    [("[measured]\nuse_in_model = true\nm1_g = 1.5\n", "[measured]: not used by a sweep"),
     ('[render]\nrule = "worst_case"\n', "render.rule = 'worst_case': not used by a sweep")],
)  # fmt: skip
def test_cli_refuses_an_unused_section_in_one_line(tmp_path, capsys, table, fragment):
    from mrclutch.cli.main import main

    path = write_spec(tmp_path, {k: SECTIONS[k] for k in ("sweep", "parameters")}, table)
    assert main(["sweep", str(path), "--out", str(tmp_path / "r.csv"), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and fragment in err
    assert not (tmp_path / "r.csv").exists()


def test_a_clutch_table_is_applied_over_the_base_preset(tmp_path):
    """`[clutch]` in a spec: fixed dimensions over `[sweep]` base (it was dropped before)."""
    spec, rest = load_spec(write_spec(tmp_path, {k: SECTIONS[k] for k in
                                                 ("sweep", "parameters", "clutch")}))  # fmt: skip
    assert spec.base.drum_thickness == pytest.approx(0.3e-3)
    assert spec.base.gap == preset("paper").gap and "clutch" not in rest
    path = write_spec(tmp_path, {"sweep": SECTIONS["sweep"], "parameters": SECTIONS["parameters"],
                                 "clutch": 'base = "paper"'})  # fmt: skip
    with pytest.raises(ParameterError, match=r"\[clutch\]: dimensions .* \[sweep\] base"):
        load_spec(path)


def test_an_evaluator_error_leaves_no_header_only_file(tmp_path):
    """A chunk the evaluator refuses on a new output: no file is left (a header-only CSV
    and its record were left before); after recorded chunks, the file keeps them."""
    spec, _ = load_spec(write_spec(tmp_path, {k: SECTIONS[k] for k in ("sweep", "parameters")}))

    def refuses(after):
        calls = []

        def evaluate(fields):
            calls.append(1)
            if len(calls) > after:
                raise ParameterError("core: unknown DrumClutch field")
            return geometric_outputs(fields)

        return evaluate

    out = tmp_path / "r.csv"
    with pytest.raises(ParameterError, match="unknown DrumClutch field"):
        run_sweep(spec, out, refuses(0), OUTPUTS, progress=False)
    assert not out.exists() and not (tmp_path / "r.csv.meta.json").exists()
    with pytest.raises(ParameterError, match="unknown DrumClutch field"):
        run_sweep(spec, tmp_path / "p.parquet", refuses(0), OUTPUTS, progress=False)
    assert not (tmp_path / "p.parquet").exists()
    with pytest.raises(ParameterError):
        run_sweep(spec, out, refuses(2), OUTPUTS, progress=False, max_pending=1)
    meta = json.loads((tmp_path / "r.csv.meta.json").read_text())
    assert [c["chunk"] for c in meta["chunks"]] == [0, 1]
    lines = out.read_text().splitlines()
    assert len(lines) == 1 + 4 and all(line.count(",") == 4 for line in lines)
    res = run_sweep(spec, out, geometric_outputs, OUTPUTS, resume=True, progress=False)
    assert res.complete and res.resumed_from == 4


@pytest.mark.parametrize("name", ["r.csv", "r.parquet"])
def test_resume_and_repair_keep_working_with_a_material_column(tmp_path, name):
    """Material names in the file (CSV text, a Parquet dictionary column): a resumed run
    and a repaired one equal the uninterrupted run byte for byte."""
    sections = {"sweep": 'mode = "grid"\nchunk_size = 2',
                "parameters": 'fluid = {values = ["MRF-122EG", "MRF-140CG"]}\n'
                              "gap_mm = {values = [0.3, 0.4, 0.5, 0.6]}"}  # fmt: skip
    spec, _ = load_spec(write_spec(tmp_path, sections))
    whole, out = tmp_path / f"whole-{name}", tmp_path / name
    run_sweep(spec, whole, dims_only(geometric_outputs), OUTPUTS, progress=False)
    part = run_sweep(spec, out, dims_only(InterruptAfter(2)), OUTPUTS, progress=False)
    assert not part.complete
    res = run_sweep(spec, out, dims_only(geometric_outputs), OUTPUTS, resume=True,
                    progress=False)  # fmt: skip
    assert res.complete and res.resumed_from == 4

    def files(p):
        return {f.name: f.read_bytes() for f in p.iterdir()} if p.is_dir() else p.read_bytes()

    assert files(out) == files(whole)
    if name.endswith(".csv"):  # a name altered in chunk 2's first row
        text = out.read_text()
        out.write_text(text.replace("\n4,mrf_140cg,", "\n4,mrf_122eg,", 1))
    else:
        (out / "part-000002.parquet").write_bytes(b"not parquet")
    with pytest.raises(ParameterError, match=r"chunk 2 .* cannot resume; run again with --repair"):
        run_sweep(spec, out, dims_only(geometric_outputs), OUTPUTS, resume=True, progress=False)
    res = run_sweep(spec, out, dims_only(geometric_outputs), OUTPUTS, repair=True,
                    progress=False)  # fmt: skip
    assert res.repaired == (2,) and files(out) == files(whole)
    assert read_results(out)["fluid"].tolist() == ["mrf_122eg"] * 4 + ["mrf_140cg"] * 4
