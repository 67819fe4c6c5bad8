"""A record corrected with the parameters flight path reconstruction estimated: biases,
scale factors and time shifts removed, vane angles moved to the CG.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping

import numpy as np

from flightid.channels import CHANNELS
from flightid.identification.compatibility.kinematics import Problem, simulate, vane_angles
from flightid.identification.compatibility.parameters import INPUTS, PARAMETERS
from flightid.identification.estimate import Estimate
from flightid.record import FlightRecord


def _shift(t: np.ndarray, x: np.ndarray, tau: float) -> np.ndarray:
    """x(t + tau): undo a delay tau (s); the end values are held."""
    return x if tau == 0 else np.interp(t + tau, t, x)


def correct(record: FlightRecord, values: Mapping[str, float],
            reconstruction: tuple[Problem, Estimate] | None = None) -> FlightRecord:
    """The record with calibration ``values`` applied.

    Inputs: x = (m - bias) / (1 + scale). V: (m(t + delay) - bias) / (1 + scale). Vanes:
    (m(t + delay) - bias) / (1 + k), then the vane-position effect removed exactly by a
    fixed-point iteration on ``vane_angles`` with the corrected rates. Attitudes, h,
    north, east: m(t + delay) - bias (psi keeps its wrapping).

    Parameters
    ----------
    record : FlightRecord
        The measured flight, SI channels.
    values : mapping of str to float
        Calibration parameters (names of ``PARAMETERS``), SI; missing ones at their defaults.
    reconstruction : tuple of (Problem, Estimate), optional
        With it the modelled outputs and u, v, w are added as ``<channel>_reconstructed``
        and the estimates are documented in ``meta.extra['compatibility']``.

    Returns
    -------
    FlightRecord
        The corrected record.
    """
    P = {n: float(values.get(n, p.default)) for n, p in PARAMETERS.items()}
    t = record.time
    ch: dict[str, np.ndarray] = {}
    how: dict[str, str] = {}
    for c in INPUTS:
        if c in record:
            ch[c] = (record[c] - P[f"bias_{c}"]) / (1.0 + P[f"scale_{c}"])
            how[c] = f"(m - {P[f'bias_{c}']:.6g}) / (1 + {P[f'scale_{c}']:.6g})"
    for c in ("phi", "theta", "h", "north", "east"):
        if c in record:
            ch[c] = _shift(t, record[c], P[f"delay_{c}"]) - P[f"bias_{c}"]
            how[c] = f"m(t + {P[f'delay_{c}']:.4g} s) - {P[f'bias_{c}']:.6g}"
    if "psi" in record:
        raw = record["psi"]
        shifted = _shift(t, np.unwrap(raw), P["delay_psi"]) - P["bias_psi"]
        ch["psi"] = shifted + (raw[0] - np.unwrap(raw)[0])
        if raw.min() >= 0 and raw.max() <= 2 * math.pi:
            ch["psi"] = np.mod(ch["psi"], 2 * math.pi)
        how["psi"] = f"m(t + {P['delay_psi']:.4g} s) - {P['bias_psi']:.6g}"
    if "V" in record:
        ch["V"] = (_shift(t, record["V"], P["delay_V"]) - P["bias_V"]) / (1.0 + P["scale_V"])
        how["V"] = f"(m(t + {P['delay_V']:.4g} s) - {P['bias_V']:.6g}) / (1 + {P['scale_V']:.6g})"
    if all(c in record for c in ("V", "alpha", "beta")):
        ch.update(_correct_vanes(record, P, ch))
        for c, k in (("alpha", "upwash_alpha"), ("beta", "sidewash_beta")):
            pos = ", ".join(f"{P[f'vane_{c}_{a}']:.4g}" for a in "xyz")
            how[c] = (f"(m(t + {P[f'delay_{c}']:.4g} s) - {P[f'bias_{c}']:.6g}) / "
                      f"(1 + {P[k]:.6g}), vane at ({pos}) m removed")
    units = dict(record.meta.units)
    extra = dict(record.meta.extra)
    if reconstruction is not None:
        problem, estimate = reconstruction
        for o in problem.outputs:
            ch[f"{o}_reconstructed"] = estimate.outputs[o]["model"].copy()
            units[f"{o}_reconstructed"] = CHANNELS[o].unit
        _, states = simulate(problem, values)
        for j, s in enumerate(("u", "v", "w")):
            ch[f"{s}_reconstructed"] = states[:, j]
            units[f"{s}_reconstructed"] = CHANNELS[s].unit
        extra["compatibility"] = {
            "method": "flight path reconstruction (identification/compatibility/reconstruction.py)",
            "estimates": {n: {"value": float(v), "std": float(s), "unit": PARAMETERS[n].unit}
                          for n, v, s in zip(estimate.names, estimate.values, estimate.std,
                                             strict=True)},
            "unidentifiable": dict(estimate.unidentifiable),
            "applied": {n: v for n, v in P.items() if v != PARAMETERS[n].default
                        and not n.startswith("x0_")},
            "corrections": how,
            "reconstructed": "channels <name>_reconstructed: the kinematic model outputs",
            "gravity_m_s2": problem.gravity,
        }
    meta = dataclasses.replace(record.meta, units=units, extra=extra)
    if reconstruction is not None:
        meta.provenance = (f"{record.meta.provenance}; corrected by flight path "
                           "reconstruction").lstrip("; ")
    return FlightRecord(t.copy(), {**record.channels, **ch}, meta)


def _correct_vanes(record: FlightRecord, P: Mapping[str, float],
                   ch: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Corrected alpha and beta: calibration undone, then the vane-position effect."""
    t = record.time
    av = (_shift(t, record["alpha"], P["delay_alpha"]) - P["bias_alpha"]) / (1 + P["upwash_alpha"])
    bv = (_shift(t, record["beta"], P["delay_beta"]) - P["bias_beta"]) / (1 + P["sidewash_beta"])
    apos = tuple(P[f"vane_alpha_{a}"] for a in "xyz")
    bpos = tuple(P[f"vane_beta_{a}"] for a in "xyz")
    if not any(apos) and not any(bpos):
        return {"alpha": av, "beta": bv}
    V = ch["V"]
    p, q, r = (ch.get(c, record[c]) if c in record else np.zeros_like(t) for c in ("p", "q", "r"))
    alpha, beta = av.copy(), bv.copy()
    for _ in range(6):  # contraction: the position effect is a small fraction of the angle
        u = V * np.cos(alpha) * np.cos(beta)
        v = V * np.sin(beta)
        w = V * np.sin(alpha) * np.cos(beta)
        a_model, b_model = vane_angles(u, v, w, p, q, r, apos, bpos)
        alpha = alpha + (av - a_model)
        beta = beta + (bv - b_model)
    return {"alpha": alpha, "beta": beta}
