"""The sidecar ``<out>.meta.json`` of a sweep's output: what wrote the rows (the spec's
fingerprint, the model's version, the output columns) and, as they are written, every
chunk's row range, byte range (or Parquet part) and SHA-256. A resume reads it back
(``_recorded``) and refuses, saying what changed (``_what_changed``), output of another
spec or model.
"""

from __future__ import annotations

import functools
import hashlib
import importlib.util
import json
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import mrclutch
from geometry.atomic import write_text
from geometry.materials import DATA as MATERIAL_DATA
from geometry.validation import ParameterError
from mrclutch.outputs import OUTPUTS, describe
from mrclutch.sweep.spec import SweepSpec

#: The packages whose code computes a sweep's rows (``model_version`` digests their
#: sources); their subfolders in ``CODE_ASIDE`` (the command line) compute none.
MODEL_PACKAGES = ("geometry", "magnetics", "mrclutch")
CODE_ASIDE = (("mrclutch", "cli"),)


def _package_folders(name: str) -> list[Path]:
    found = importlib.util.find_spec(name)
    return [Path(f) for f in (found.submodule_search_locations or [])] if found else []


def code_digest() -> str:
    """SHA-256 of the model's source: every ``.py`` file of ``MODEL_PACKAGES`` (its path in
    the package and its bytes), the command line aside. A code change changes it, whether
    or not the version number was raised."""
    digest = hashlib.sha256()
    for name in MODEL_PACKAGES:
        aside = [Path(*rest) for pkg, *rest in CODE_ASIDE if pkg == name]
        for folder in _package_folders(name):
            for f in sorted(folder.rglob("*.py")):
                rel = f.relative_to(folder)
                if any(rel.is_relative_to(a) for a in aside):
                    continue
                digest.update(f"{name}/{rel.as_posix()}".encode() + b"\0" + f.read_bytes())
    return digest.hexdigest()


@functools.lru_cache(maxsize=1)
def model_version() -> str:
    """The model that writes a sweep's rows: the installed mrclutch's version, a digest of
    the data its models read (the error map, the materials library) and one of its code
    (``code_digest``: a resume across an edit of the model's code wrote rows of two models
    into one file while the version number stayed). A resume of rows another model wrote
    is refused (``run_sweep``)."""
    folders = [f / "data" for f in _package_folders("magnetics")]
    digest = hashlib.sha256()
    for f in sorted([*MATERIAL_DATA.glob("*.toml"), *(x for d in folders for x in d.glob("*"))]):
        if f.is_file():
            digest.update(f.name.encode() + b"\0" + f.read_bytes())
    return (f"mrclutch {mrclutch.__version__}, model data {digest.hexdigest()[:12]}, "
            f"code {code_digest()[:12]}")  # fmt: skip


def _meta_path(out: Path) -> Path:
    return out.with_name(out.name + ".meta.json")


def _meta(spec: SweepSpec, outputs: Sequence[str]) -> dict[str, Any]:
    """What the ``.meta.json`` sidecar (and each Parquet part's schema) records."""
    return {
        "fingerprint": spec.fingerprint(),
        "n_designs": spec.n_designs,
        "outputs": list(outputs),
        "columns": describe([k for k in outputs if k in OUTPUTS]),  # units and meanings
        # a material axis' column holds these names (a Parquet dictionary column)
        "categories": {p.column: list(p.categories) for p in spec.params if p.categories},
        "inputs": spec.input_digests(),  # what changed, when a resume is refused
        "model": model_version(),
    }


def _what_changed(old: dict[str, Any], meta: dict[str, Any]) -> list[str]:
    """What differs between the record of an earlier run and this one's (empty: nothing)."""
    if all(old.get(k) == v for k, v in meta.items()):
        return []
    was = old.get("inputs")
    if not isinstance(was, dict):
        return ["its record names none of the spec's sections (an older mrclutch wrote it)"]
    now = meta["inputs"]
    what = [f"{k} {'added' if k not in was else 'removed' if k not in now else 'changed'}"
            for k in sorted(set(was) | set(now)) if was.get(k) != now.get(k)]  # fmt: skip
    if old.get("model") != meta["model"]:
        what.append(f"the model changed (was {old.get('model')}, now {meta['model']})")
    if old.get("outputs") != meta["outputs"] or old.get("columns") != meta["columns"]:
        what.append("the output columns differ (--with)")
    return what or ["the sweep's settings changed"]


def _read_or_refuse(path: Path, parse: Callable[[str], Any]) -> Any:
    """``parse`` of a file left by an earlier run; a corrupt one refuses the resume in one line."""
    try:
        return parse(path.read_text(encoding="utf-8"))
    except (ValueError, OSError) as exc:  # JSONDecodeError and UnicodeDecodeError too
        raise ParameterError(
            f"{path}: unreadable ({type(exc).__name__}); cannot resume; pass --overwrite "
            "to start again"
        ) from None


#: Least time between two rewrites of the ``.meta.json`` chunk records (s). Chunks written
#: since the last rewrite are not yet recorded: a resume cuts and recomputes them.
META_INTERVAL = 0.5


def _digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _chunk_rows_range(spec: SweepSpec, k: int) -> list[int]:
    return [k * spec.chunk_size, min((k + 1) * spec.chunk_size, spec.n_designs)]


def _write_meta(out: Path, meta: dict[str, Any], records: list[dict[str, Any]]) -> None:
    write_text(_meta_path(out), json.dumps({**meta, "chunks": records}))


def _recorded(out: Path, meta: dict[str, Any], spec: SweepSpec, sink: Any
              ) -> list[dict[str, Any]]:  # fmt: skip
    """The chunk records of the ``.meta.json`` beside ``out``, checked for shape; one line
    refusing the resume when it is missing, of another spec or damaged."""
    mp = _meta_path(out)
    if not mp.exists():
        raise ParameterError(f"{mp}: missing; cannot verify {out}; cannot resume; pass "
                             "--overwrite to start again")  # fmt: skip
    old = _read_or_refuse(mp, json.loads)
    if not isinstance(old, dict):
        raise ParameterError(f"{mp}: not a sweep's record; cannot resume; pass --overwrite "
                             "to start again")  # fmt: skip
    changed = _what_changed(old, meta)
    if changed:  # its rows and the rest would come from two sets of inputs
        raise ParameterError(f"{out}: written by a different sweep spec or model "
                             f"({'; '.join(changed)}); cannot resume; pass --overwrite to "
                             "start again")  # fmt: skip
    records = old.get("chunks")
    if records is None:
        raise ParameterError(f"{mp}: records no chunk checksums (an older mrclutch wrote "
                             "it); cannot verify; pass --overwrite to start again")  # fmt: skip
    keys = {"chunk", "rows", "bytes", "sha256"}
    ok = isinstance(records, list) and len(records) <= spec.n_chunks
    for k, r in enumerate(records if ok else []):
        prev = records[k - 1] if k else None
        ok = (isinstance(r, dict) and keys <= set(r) and r["chunk"] == k
              and r["rows"] == _chunk_rows_range(spec, k) and isinstance(r["bytes"], int)
              and r["bytes"] >= 0 and isinstance(r["sha256"], str)
              and sink.well_formed(r, k, prev))  # fmt: skip
        if not ok:
            break
    if not ok:
        raise ParameterError(f"{mp}: its chunk records are damaged; cannot resume; pass "
                             "--overwrite to start again")  # fmt: skip
    return records
