"""The generated table of docs/materials.md: each material's coercivity and remanence (its
``[hysteresis]`` table, magnetics.hysteresis), the fluid's τy(T) coefficient
(``magnetics.hot``) and its lifetime dissipated energy (``magnetics.life``), each with the
source keys its data file gives or "unverified" where the file lists it so.

    python -m magnetics.materials_table            # print the table (Markdown)
    python -m magnetics.materials_table --write    # rewrite it in docs/materials.md

The table sits between ``<!-- materials-table -->`` and ``<!-- /materials-table -->``;
tests/magnetics/test_materials_table.py checks the doc holds what this prints.
"""

from __future__ import annotations

import re
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from geometry import docblock
from geometry.materials import RECORDS, is_builtin
from magnetics.hot import tau_y_coefficient
from magnetics.materials import FLUIDS

DOC = Path(__file__).resolve().parents[1] / "docs" / "materials.md"
BEGIN, END = "<!-- materials-table -->", "<!-- /materials-table -->"
_KEY = re.compile(r"\[([a-z][a-z0-9-]{4,})\]")
NONE = "—"


def _keys(*texts: Any) -> str:
    """The citation keys in the source strings, in order, once each ("—" if none)."""
    seen: dict[str, None] = {}
    for t in texts:
        for k in _KEY.findall(str(t or "")):
            seen[k] = None
    return " ".join(f"[{k}]" for k in seen) or NONE


def _cell(value: str, field: str, rec: Mapping[str, Any]) -> str:
    """``value``, marked unverified where the record lists ``field`` so."""
    return f"{value} (unverified)" if field in rec.get("unverified", ()) else value


def rows() -> list[list[str]]:
    """One row per steel and fluid of the library: name, kind, Hc, Br, τy(T) coefficient,
    LDE, sources. A user's material file loaded in the same process is not the library's,
    so it has no row (the doc must not depend on what ran before)."""
    out = []
    for name, rec in RECORDS.items():
        if not is_builtin(name):
            continue
        kind = rec["kind"]
        if kind not in ("steel", "fluid"):
            continue
        hc = br = coef = lde = NONE
        src: list[Any] = []
        hyst = rec.get("hysteresis")
        if isinstance(hyst, Mapping):
            if "coercivity_A_per_m" in hyst:
                hc = _cell(f"{hyst['coercivity_A_per_m']:g}", "hysteresis.coercivity_A_per_m", rec)
            if "remanence_T" in hyst:
                br = _cell(f"{hyst['remanence_T']:g}", "hysteresis.remanence_T", rec)
            src.append(hyst.get("source"))
        if kind == "fluid":
            fl = FLUIDS[name]
            c = tau_y_coefficient(fl)
            if c is not None:
                coef = _cell(f"{c * 100:.3f}", "carrier_expansion", rec)
            if fl.lifetime_energy is not None:
                lde = _cell(f"{fl.lifetime_energy * 1e-12:g}", "lifetime_dissipated_energy", rec)
            src += [rec.get("tau_y_temperature_source"), rec.get("carrier_expansion_source"),
                    rec.get("lifetime_dissipated_energy_source")]  # fmt: skip
        out.append([f"`{name}` ({rec['label']})" if rec["label"] != name else f"`{name}`",
                    kind, hc, br, coef, lde, _keys(*src)])  # fmt: skip
    return out


def table() -> str:
    """The Markdown table (with its header)."""
    head = ["material", "kind", "coercivity Hc (A/m)", "remanence Br (T)",
            "τy(T) coefficient at 20 °C (%/K)", "lifetime dissipated energy (MJ/mL)",
            "sources"]  # fmt: skip
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    lines += ["| " + " | ".join(r) + " |" for r in rows()]
    return "\n".join(lines)


def block() -> str:
    """What the doc holds between the markers (the command that writes it, then the table)."""
    return docblock.block(BEGIN, END, "python -m magnetics.materials_table --write", table())


def replaced(text: str) -> str:
    """``text`` with its marked block replaced by ``block()``; ValueError without markers."""
    return docblock.replaced(text, BEGIN, END, block())


def main(argv: list[str] | None = None) -> int:
    """Print the table, or rewrite it in docs/materials.md (``--write``)."""
    return docblock.main(argv, "python -m magnetics.materials_table", DOC, table, replaced)


if __name__ == "__main__":
    sys.exit(main())
