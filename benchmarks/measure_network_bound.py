"""Build the reluctance network's error bound over every section dimension (issue 31) and
check it on designs it was not built from; write `magnetics/data/network_bound.json`
(read by magnetics.network_bound).

No new FEM runs: the FEM torques come from `benchmarks/data/fem_doe.json`
(measure_fem_doe.py: a Sobol design of experiments over 16 section inputs and N·I, the
build set, and fresh uniform random designs with another seed, the check set). Here the
network's torque is computed at the same designs and ampere-turns (the default torque
convention, the FEM's in the same convention) and the signed error e = network/FEM − 1.

The estimate ê (a ridge quadratic, RIDGE, in the inputs scaled to [0, 1], lengths and N·I
on log axes) is fitted on the build set, and the bound |ê| + q takes q by cross-conformal
prediction (FOLDS folds by design: each build point's score |e| − |ê| with ê fitted
without its design, q their ⌈(n + 1)·COVERAGE⌉-th smallest). The check set then measures
the bound's coverage and tightness on designs never used: the share of designs × currents
whose |e| lies inside the bound, the median bound and the median |e|, stored with it.

    python benchmarks/measure_network_bound.py [--compare | --json]    # ~5 s

``--json`` prints the measurement (q, the build and check figures) and writes nothing;
``--compare`` cross-validates the variants (linear or log axes, linear or quadratic
estimate, ridge weight) on the build set alone and writes nothing.
"""

from __future__ import annotations

import datetime
import json
import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from magnetics.network_bound import (  # noqa: E402
    AMPERE_TURNS,
    DATA_FILE,
    DEFAULT_MATERIALS,
    NetworkBound,
)

DOE = ROOT / "benchmarks" / "data" / "fem_doe.json"
COVERAGE = 0.95  # the stated coverage of the bound (designs × currents)
FOLDS = 5  # cross-conformal folds, by design (a design's three currents stay together)
RIDGE = 1e-3  # ridge weight on the quadratic's coefficients (scaled inputs in [0, 1])
#: Inputs scaled on a log axis (every length and N·I: the errors follow ratios of them).
LOG = True


def network_errors(rows: list[dict], convention: str) -> tuple[dict, np.ndarray, np.ndarray]:
    """(fields of the designs, N·I (S, 3), e (S, 3)) of DOE ``rows`` by the network."""
    from geometry import regions
    from geometry.params import broadcast_fields, valid
    from magnetics.network import network_from_regions
    from magnetics.torque import network_gap_torque
    from mrclutch.design import design_preset

    base = vars(design_preset("paper").clutch)
    turns = 140.0
    fields = {k: np.array([r["design"].get(k, v) for r in rows], dtype=float)
              for k, v in base.items()}  # fmt: skip
    fields["coil_turns"] = np.full(len(rows), turns)
    p = broadcast_fields(fields)
    ni = np.array([r["design"]["ampere_turns"] for r in rows], dtype=float)
    cur = ni / turns

    def one(rg, idx):  # type: ignore[no-untyped-def]
        net = network_from_regions(rg)
        return {"t": network_gap_torque(net, cur[idx], convention=convention).sum(-1)}

    net = regions.per_topology(p, valid(p), one)["t"]
    fem = np.array([[math.nan] * 3 if r["torque"] is None else r["torque"][convention]
                    for r in rows], dtype=float)  # fmt: skip
    return fields, ni, net / fem - 1.0


def scaled(bound: NetworkBound, fields: dict, ni: np.ndarray) -> np.ndarray:
    """x (S·3, k): every design's inputs scaled as the bound scales them, repeated for its
    three currents (the runtime's own scaling: one implementation)."""
    rep = {k: np.repeat(v, ni.shape[1]) for k, v in fields.items()}
    x, inside, _ = bound.scaled(rep, ni.ravel())
    assert inside.all()
    return x


def quad_basis(x: np.ndarray, degree: int = 2) -> tuple[np.ndarray, list[tuple[int, int]]]:
    """[1, x, x_i x_j (i ≤ j)] and the (i, j) of the products (degree 1: [1, x])."""
    k = x.shape[1]
    pairs = [(i, j) for i in range(k) for j in range(i, k)] if degree == 2 else []
    cols = [np.ones(len(x)), *x.T, *(x[:, i] * x[:, j] for i, j in pairs)]
    return np.stack(cols, axis=1), pairs


def fit_estimate(x: np.ndarray, e: np.ndarray, ridge: float = RIDGE, degree: int = 2
                 ) -> tuple[float, np.ndarray, np.ndarray]:  # fmt: skip
    """(c, b, A) of the ridge quadratic ê = c + b·x + xᵀAx fitted to ``e``."""
    k = x.shape[1]
    basis, pairs = quad_basis(x, degree)
    reg = ridge * np.eye(basis.shape[1])
    reg[0, 0] = 0.0  # no penalty on the constant
    coef = np.linalg.solve(basis.T @ basis + len(basis) * reg, basis.T @ e)
    a = np.zeros((k, k))
    for (i, j), v in zip(pairs, coef[k + 1 :], strict=True):
        a[i, j] += v  # x_i x_j: upper triangle (xᵀAx sums each product once)
    return float(coef[0]), coef[1 : k + 1], a


def estimate(c: float, b: np.ndarray, a: np.ndarray, x: np.ndarray) -> np.ndarray:
    return c + x @ b + np.einsum("pi,ij,pj->p", x, a, x)


def cross_conformal(x: np.ndarray, e: np.ndarray, design: np.ndarray, ridge: float = RIDGE,
                    degree: int = 2) -> tuple[float, np.ndarray]:  # fmt: skip
    """(q, out-of-fold ê): the score |e| − |ê| of every build point with ê fitted without
    its design's fold (FOLDS folds), q its ⌈(n + 1)·COVERAGE⌉-th smallest."""
    oof = np.empty_like(e)
    for f in range(FOLDS):
        test = design % FOLDS == f
        oof[test] = estimate(*fit_estimate(x[~test], e[~test], ridge, degree), x[test])
    scores = np.sort(np.abs(e) - np.abs(oof))
    n = scores.size
    return float(scores[min(math.ceil((n + 1) * COVERAGE), n) - 1]), oof


def measure(convention: str | None = None) -> dict:
    """Fit on the DOE's build set, check on its check set: the data file's content."""
    from magnetics.torque import DEFAULT_CONVENTION

    convention = convention or DEFAULT_CONVENTION
    doe = json.loads(DOE.read_text())
    ranges = {**{k: tuple(v) for k, v in doe["ranges"].items()},
              AMPERE_TURNS: tuple(doe["ampere_turns_range"])}  # fmt: skip
    log = tuple(k for k in ranges if k != "n_drums") if LOG else ()
    frame = NetworkBound(DEFAULT_MATERIALS, ranges, log, 0.0, (), (), 0.0, COVERAGE, {})
    fb, nib, eb = network_errors(doe["build"], convention)
    fc, nic, ec = network_errors(doe["check"], convention)
    xb, eb = scaled(frame, fb, nib), eb.ravel()
    design = np.repeat(np.arange(len(doe["build"])), 3)
    ok = np.isfinite(eb)
    q, _ = cross_conformal(xb[ok], eb[ok], design[ok])
    c, b, a = fit_estimate(xb[ok], eb[ok])
    xc, ec = scaled(frame, fc, nic), ec.ravel()
    okc = np.isfinite(ec)
    bound_c = np.abs(estimate(c, b, a, xc[okc])) + q
    inside = np.abs(ec[okc]) <= bound_c
    check = {
        "designs": len(doe["check"]),
        "points": int(okc.sum()),
        "coverage": round(float(inside.mean()), 4),
        "median_bound": round(float(np.median(bound_c)), 5),
        "median_abs_error": round(float(np.median(np.abs(ec[okc]))), 5),
        "max_abs_error": round(float(np.max(np.abs(ec[okc]))), 5),
        "within_5pct": round(float(np.mean(np.abs(ec[okc]) <= 0.05)), 4),
        "within_10pct": round(float(np.mean(np.abs(ec[okc]) <= 0.10)), 4),
        "seed": doe["seeds"]["check"],
    }
    r = lambda v: [round(float(t), 9) for t in v]  # noqa: E731
    return {
        "ranges": {k: list(v) for k, v in ranges.items()},
        "log_scaled": list(log),
        "convention": convention,
        "estimate": {"c": round(c, 9), "b": r(b), "a": [r(row) for row in a]},
        "q": round(q, 6),
        "coverage": COVERAGE,
        "build": {"designs": len(doe["build"]), "points": int(ok.sum()),
                  "seed": doe["seeds"]["build"],
                  "median_abs_error": round(float(np.median(np.abs(eb[ok]))), 5)},
        "check": check,
    }  # fmt: skip


def compare() -> None:
    """Variants of the bound on the build set alone (the check set is not looked at):
    out-of-fold R² of the estimate, the cross-conformal q, and the median bound over the
    median |error| on the build designs (out of fold)."""
    from magnetics.torque import DEFAULT_CONVENTION

    doe = json.loads(DOE.read_text())
    ranges = {**{k: tuple(v) for k, v in doe["ranges"].items()},
              AMPERE_TURNS: tuple(doe["ampere_turns_range"])}  # fmt: skip
    fb, nib, eb = network_errors(doe["build"], DEFAULT_CONVENTION)
    eb = eb.ravel()
    design = np.repeat(np.arange(len(doe["build"])), 3)
    for log in (False, True):
        names = tuple(k for k in ranges if k != "n_drums") if log else ()
        frame = NetworkBound(DEFAULT_MATERIALS, ranges, names, 0.0, (), (), 0.0, COVERAGE, {})
        x = scaled(frame, fb, nib)
        for degree in (1, 2):
            for ridge in (1e-4, 1e-3, 1e-2):
                q, oof = cross_conformal(x, eb, design, ridge, degree)
                r2 = 1 - np.mean((eb - oof) ** 2) / np.var(eb)
                ratio = np.median(np.abs(oof) + q) / np.median(np.abs(eb))
                print(f"{'log' if log else 'linear':6s} axes, degree {degree}, ridge "
                      f"{ridge:g}: out-of-fold R² {r2:.3f}, q {q:.4f}, median bound / "
                      f"median |error| {ratio:.2f}")  # fmt: skip


def main() -> None:
    if "--compare" in sys.argv[1:]:
        compare()
        return
    data = measure()
    if "--json" in sys.argv[1:]:  # print the measurement, write nothing (docs/figures.toml)
        print(json.dumps({k: data[k] for k in ("q", "coverage", "build", "check")}))
        return
    doc = {
        "about": (
            "The reluctance network's torque error bound against the FEM (signed network/FEM "
            "- 1) over every section dimension and the coil's ampere-turns, per material set "
            "(steel+fluid): estimate c + b.x + x'Ax on the inputs scaled to [0, 1] over ranges "
            "(SI; ampere_turns in A; log_scaled ones on a log axis), bound |estimate| + q with "
            "q the cross-conformal quantile at coverage; check: measured on the "
            f"fresh designs of benchmarks/data/fem_doe.json; written on "
            f"{datetime.date.today()}; do not edit by hand (magnetics.network_bound)."
        ),
        "generated_by": "python benchmarks/measure_network_bound.py",
        "material_sets": {DEFAULT_MATERIALS: data},
    }
    DATA_FILE.write_text(json.dumps(doc, indent=1) + "\n")
    c = data["check"]
    print(f"wrote {DATA_FILE}: q {data['q']:.3f}; check ({c['designs']} fresh designs, "
          f"{c['points']} points): coverage {c['coverage']:.1%}, median bound "
          f"{c['median_bound']:.2%}, median |error| {c['median_abs_error']:.2%} (ratio "
          f"{c['median_bound'] / c['median_abs_error']:.2f}), max |error| "
          f"{c['max_abs_error']:.2%}")  # fmt: skip


if __name__ == "__main__":
    main()
