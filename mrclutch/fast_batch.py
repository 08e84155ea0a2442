"""The fast path on arrays of designs: ``evaluate_batch`` (the sweep's and the
optimiser's rows, the same physics as ``evaluate(design, "fast")``) and its picklable
``BatchEvaluator`` with the opt-in columns (``outputs.SWEEP_OPTIONAL``)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from geometry import regions
from geometry.mass import region_mass
from geometry.materials import MaterialChoice
from geometry.params import valid
from geometry.validation import ParameterError, check_choice
from magnetics import thermal
from magnetics.amplifier import supply_current
from magnetics.circuit import linear_flux, path_from_regions, solve_flux
from magnetics.drag import coupled_fluid_inertia, drag_terms, totals
from magnetics.dynamics import torque_response
from magnetics.error_map import error_bound
from magnetics.network import network_from_regions
from magnetics.network_bound import FEATURES, solution_features
from magnetics.torque import continuous_torque, network_yield_at
from mrclutch.at_hand import mr_at_hand
from mrclutch.batch import batch_fields
from mrclutch.clutch import dynamic_range_db, fluid_limit
from mrclutch.design import ClutchDesign, current_limit
from mrclutch.duty import DUTY_COLUMNS, HOT_COLUMNS, duty_batch
from mrclutch.feel import FEEL_COLUMNS, feel_batch
from mrclutch.haptics.hand import backdrive_force
from mrclutch.haptics.model import (
    max_passive_stiffness,
    metrics_batch,
)
from mrclutch.haptics.zwidth import zwidth as zwidth_of
from mrclutch.hot_rows import hot_batch
from mrclutch.outputs import SWEEP_COLUMNS, SWEEP_OPTIONAL
from mrclutch.robust_search import stable_stiffness_batch
from mrclutch.trust import material_set

# ---- the vectorised fast path for sweeps -----------------------------------------------


def _material_bounds(
    p: Mapping[str, np.ndarray], current: np.ndarray, mats: MaterialChoice | np.ndarray,
    features: Mapping[str, np.ndarray],
) -> np.ndarray:  # fmt: skip
    """The network's error bound of every row at its material set (``trust.material_set``;
    magnetics.network_bound: inf for a set never measured), from its network's solution
    ``features`` at that current (``solution_features``, each (S,))."""
    if isinstance(mats, MaterialChoice):
        return np.asarray(
            error_bound(p, "network", current, material_set(mats), features)[1], float
        )
    keys = np.array([material_set(m) for m in mats], dtype=object)
    out = np.full(keys.shape, np.inf)
    for key in dict.fromkeys(keys.tolist()):
        rows = keys == key
        sub = {k: np.asarray(v)[rows] for k, v in p.items()}
        feats = {k: np.asarray(v)[rows] for k, v in features.items()}
        out[rows] = error_bound(sub, "network", np.asarray(current)[rows], key, feats)[1]
    return out


@dataclass(frozen=True)
class BatchEvaluator:
    """Picklable fast-path evaluator of arrays of designs around a base ClutchDesign.

    Fields a sweep does not vary come from ``base.clutch``; operating point and
    transmission are the base design's. Invalid designs (DrumClutch validation fails) get
    ``valid = 0`` and NaN outputs; they are computed on the base geometry meanwhile so no
    invalid number ever reaches the solvers.
    """

    base: ClutchDesign
    optional: tuple[str, ...] = ()  # of ``SWEEP_OPTIONAL``: columns after SWEEP_COLUMNS

    def __post_init__(self) -> None:
        for key in self.optional:
            check_choice("optional column", key, SWEEP_OPTIONAL)

    @property
    def columns(self) -> tuple[str, ...]:
        """The columns of its rows, in order."""
        return (*SWEEP_COLUMNS, *(k for k in SWEEP_OPTIONAL if k in self.optional))

    def __call__(self, fields: Mapping[str, ArrayLike]) -> dict[str, np.ndarray]:
        on = set(self.optional)
        feel = tuple(k for k in self.optional if k in FEEL_COLUMNS)  # mrclutch.feel
        robust = on - {"max_passive_K_N_per_m", "max_stable_K_N_per_m", "zwidth_area_N2_s_per_m2",
                       *FEEL_COLUMNS, *DUTY_COLUMNS, *HOT_COLUMNS}  # fmt: skip
        if robust:  # over the uncertain inputs: the application's robust layer computes them
            raise ParameterError(f"{sorted(robust)[0]}: a robust column; "
                                 "use mrclutch.robust.RobustBatchEvaluator")  # fmt: skip
        out = evaluate_batch(fields, self.base, passivity="max_passive_K_N_per_m" in on,
                             stability="max_stable_K_N_per_m" in on,
                             zwidth="zwidth_area_N2_s_per_m2" in on)  # fmt: skip
        if feel:
            out.update(feel_batch(fields, self.base, feel))
        if on & set(DUTY_COLUMNS):  # the fluid's volume and life (mrclutch.duty)
            out.update(duty_batch(fields, self.base, out))
        if on & set(HOT_COLUMNS):  # the torque and b1 after the holds (mrclutch.hot_rows)
            ok = out["valid"] > 0
            inertia = out["rotor_inertia_kg_m2"][ok] + out["fluid_inertia_kg_m2"][ok]
            mr = mr_at_hand(self.base, inertia, out["drag_damping_N_m_s"][ok],
                            out["max_torque_N_m"][ok], out["clutch_mass_kg"][ok],
                            out["torque_delay_s"][ok])  # fmt: skip
            out.update(hot_batch(fields, self.base, out, mr))
        return {k: out[k] for k in self.columns}


def evaluate_batch(
    fields: Mapping[str, ArrayLike],
    base: ClutchDesign | None = None,
    *,
    passivity: bool = False,
    stability: bool = False,
    zwidth: bool = False,
    continuous: bool = True,
) -> dict[str, np.ndarray]:
    """The fast path for S designs at once; returns arrays under ``SWEEP_COLUMNS``, and
    opt-in columns after them: ``max_passive_K_N_per_m`` (``passivity``, about ×1.7 the
    cost), ``max_stable_K_N_per_m`` (``stability``: ``robust_search.stable_stiffness_batch``),
    ``zwidth_area_N2_s_per_m2`` (``zwidth``, about ×7) (``outputs.SWEEP_OPTIONAL``).
    ``continuous`` False: ``continuous_torque_N_m`` NaN, its thermal network and solves not
    computed (the hand box reads none of it; every other column is unchanged, bit for bit).

    The same physics as ``evaluate(design, "fast")``, on arrays: per drum count, the region
    table gives the analytic mass (``region_mass``), the max torque by the reluctance
    network (``network_from_regions``), the circuit (``path_from_regions``: the flux the
    torque response starts from), the drag terms (``drag_terms``), the carried fluid
    (``coupled_fluid_inertia``) and the continuous rating (``continuous_torque``, a secant on
    the network's slope T/I, its solves started from the peak's loop fluxes,
    ``network_yield_at``); the pair at the hand is ``mr_at_hand``.
    Designs that fail DrumClutch's validation get ``valid = 0`` and NaN outputs; no invalid
    number reaches a solver."""
    base = base if base is not None else ClutchDesign()
    p, mats = batch_fields(fields, base)
    ok = valid(p)
    op = base.operating
    current = np.array(np.broadcast_to(current_limit(op, p["wire_diameter"]), ok.shape), float)

    def clutch(rg: regions.Regions, rows: np.ndarray) -> dict[str, Any]:
        # the amplifier's V/R caps the current as in ClutchDesign.current_limit
        with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
            supply = supply_current(rg.fields, rg.at, base.amplifier, op.coil_temperature)
        current[rows] = np.minimum(current[rows], np.nan_to_num(supply, nan=np.inf))
        out = region_mass(rg)
        terms = drag_terms(rg, op.input_speed, op.fluid_temperature, base.support)
        out["off_torque"], out["damping"] = totals(terms)
        out["fluid_inertia"] = coupled_fluid_inertia(rg)
        path = path_from_regions(rg)
        # the loop's flux at the peak: the torque response's start (its torque is not used),
        # solved from the linear circuit's flux (solve_flux's own first iterate, computed once)
        ni = (path.turns * current[rows])[:, None]
        lin = linear_flux(path, ni)
        flux = np.abs(solve_flux(path, ni, rtol=1e-7, start=lin))
        ladder = network_from_regions(rg)
        # the network's Newton starts from its linear solution scaled by the circuit's
        # saturation there (~40 % fewer steps; the same answer to the solve's tolerance)
        with np.errstate(divide="ignore", invalid="ignore"):
            gain = flux / lin
        gain = np.where(np.isfinite(gain) & (gain > 0), gain, 1.0)
        # the peak and the continuous rating's solves on one packed network and reading
        # (``network_yield_at``: each solve starts from the last one's loop fluxes)
        at = network_yield_at(ladder)
        out["yield_torque"] = at(current[rows], gain=gain)
        # the network's error bound reads its solution at the peak (no second solve)
        for k, v in solution_features(ladder, at.flux).items():
            out[f"bound_{k}"] = v[:, 0]
        resp = torque_response(rg, current[rows], base.amplifier, base.laminations, path=path,
                               coil_temperature=op.coil_temperature,
                               flux_peak=flux[:, 0])  # fmt: skip
        out["torque_delay"] = resp.equivalent_delay
        if not continuous:  # the rating's are the last solves: nothing above reads them
            out["continuous_torque"] = np.full(np.shape(out["off_torque"]), np.nan)
            return out
        limit = fluid_limit(rg.materials)
        net = thermal.network(rg, op.ambient_temperature, limit)
        out["continuous_torque"] = continuous_torque(
            net, path, op.input_speed, out["off_torque"], op.wire_temperature_limit,
            limit, torque_at=at,
        )[1]  # fmt: skip
        return out

    fig = regions.per_topology(p, ok, clutch, mats)
    off_torque = fig["off_torque"]
    torque = fig["yield_torque"] + off_torque
    hand = {}
    if ok.any():
        inertia = fig["rotor_inertia"] + fig["fluid_inertia"]
        hp = mr_at_hand(base, inertia[ok], fig["damping"][ok], torque[ok],
                        fig["clutch_mass"][ok], fig["torque_delay"][ok])  # fmt: skip
        hand = dict(metrics_batch(hp, limits=False))
        hand["backdrive_force_N"] = backdrive_force(hp)
        if passivity:
            hand["max_passive_K_N_per_m"] = max_passive_stiffness(hp)
        if stability:
            # the D-subdivision on arrays: equal to max_stable_stiffness to 1e-9 (tests)
            hand["max_stable_K_N_per_m"] = stable_stiffness_batch(hp)
        if zwidth:
            hand["zwidth_area_N2_s_per_m2"] = zwidth_of(hp)["zwidth_area_N2_s_per_m2"]
    out = {
        "valid": ok.astype(float),
        "rotor_inertia_kg_m2": fig["rotor_inertia"],
        "rotor_mass_kg": fig["rotor_mass"],
        "clutch_mass_kg": fig["clutch_mass"],
        "diameter_m": fig["diameter"],
        "length_m": fig["length"],
        "max_torque_N_m": torque,
        # each row's material set's bound (inf where that set was never measured)
        "torque_error_bound": np.where(
            ok,
            _material_bounds(p, current, mats, {k: fig[f"bound_{k}"] for k in FEATURES}),
            np.nan,
        ),
        "fluid_inertia_kg_m2": fig["fluid_inertia"],
        "drag_damping_N_m_s": fig["damping"],
        "off_state_torque_N_m": off_torque,
        "dynamic_range_dB": dynamic_range_db(torque, off_torque),
        "continuous_torque_N_m": fig["continuous_torque"],
        "torque_delay_s": fig["torque_delay"],
    }
    opt_in = {
        "max_passive_K_N_per_m": passivity,
        "max_stable_K_N_per_m": stability,
        "zwidth_area_N2_s_per_m2": zwidth,
    }
    extra = tuple(k for k, on in opt_in.items() if on)
    columns = (*SWEEP_COLUMNS, *extra)
    for key in columns:
        if key not in out:  # a metric at the hand
            col = np.full(ok.shape, np.nan)
            if ok.any():
                col[ok] = np.broadcast_to(np.asarray(hand[key], dtype=float), (int(ok.sum()),))
            out[key] = col
    return {key: out[key] for key in columns}
