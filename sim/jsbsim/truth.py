"""Exact truth derivatives of a loaded JSBSim model at a trim point.

JSBSim's aerodynamics are evaluated at a set state without propagating: each state is
written into the initial condition and ``run_ic`` runs every model once with the
integrators suspended (dt = 0). Moments are about the actual CG (JSBSim transfers them
from the AERORP with M_cg = M_rp + (r_rp - r_cg) x F). By default the aerodynamic forces
and moments are differentiated; ``propulsion=True`` adds the propulsive ones with the
engines held at their trim state: the total derivatives a flight test identifies
(Jategaonkar 2015; Morelli & Klein 2016, ch. 3).

Controls are perturbed through the pilot commands and the derivative is taken with
respect to the surface position read back, in project signs. The alphadot derivative is
measured first (by a pitch-attitude change) and its contribution subtracted from every
other difference: dC/dx = (dC - C_alphadot * d(alphadot_hat)) / dx. Central differences
at two step sizes (h and h/4) find a kink at the trim point; a kink is reported as both
one-sided slopes and a flag, never as the average.

Rates are nondimensional: phat = p b/2V, qhat = q cbar/2V, rhat = r b/2V,
alphadot_hat = alphadot cbar/2V (Morelli & Klein 2016, ch. 3). Stability axes (Etkin &
Reid): Cl_s = Cl cos a + Cn sin a, Cn_s = Cn cos a - Cl sin a, p_s = p cos a + r sin a,
r_s = r cos a - p sin a with a the trim alpha; lift and drag are always those of the
local stability axes, CL = CX sin a - CZ cos a, CD = -CX cos a - CZ sin a.

docs/truth.md describes the method in full.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import jsbsim
import numpy as np

from flightid.record import Reference
from flightid.sim.jsbsim.aero_coefficients import coefficients
from flightid.sim.jsbsim.model import COMMANDS, Model, as_model
from flightid.sim.jsbsim.trim import Trim, apply
from flightid.units import FT, PSF, SLUG, SLUG_FT2

BODY = ("X", "Y", "Z", "l", "m", "n", "L", "D")
STABILITY = ("L", "D", "Y", "l", "m", "n")
_COEF_INDEX = {c: i for i, c in enumerate(BODY)}

# base steps (the small step is base / 4): angles rad, rates nondimensional, commands norm
STEPS = {"alpha": math.radians(0.5), "beta": math.radians(0.5), "p": 0.004, "q": 0.004,
         "r": 0.004, "de": 0.02, "da": 0.02, "dr": 0.02, "dt": 0.05}
# kink test: one-sided slopes differ by more than this (abs + rel) at the small step and
# the gap did not shrink with the step (a smooth term's gap shrinks like h)
KINK_ABS = 1e-4
KINK_REL = 0.01
_SHRINK = 0.6
ZERO = 1e-10  # |derivative| below this is roundoff and reported as 0


@dataclass(frozen=True)
class Kink:
    """A derivative whose one-sided slopes disagree at the trim point."""

    minus: float
    plus: float
    central: float
    note: str


@dataclass
class StateSpace:
    """Dimensional linear model dx/dt = A x + B u at trim (JSBSim's FGLinearization, its units)."""

    A: np.ndarray
    B: np.ndarray
    x_names: tuple[str, ...]
    u_names: tuple[str, ...]
    x_units: tuple[str, ...]
    u_units: tuple[str, ...]


@dataclass
class Truth:
    """Truth derivatives at a trim point: values by canonical name, flags for kinks."""

    aircraft: str
    axes: str
    trim: Trim
    reference: Reference
    values: dict[str, float]
    flags: dict[str, Kink] = field(default_factory=dict)
    step_spread: dict[str, float] = field(default_factory=dict)  # |central(h) - central(h/4)|
    cg_minus_aerorp_m: tuple[float, float, float] = (0.0, 0.0, 0.0)  # body axes x fwd, z down
    # trim-state quantities in SI: qbar (Pa), V (m/s), mass (kg), Ixx Iyy Izz Ixz (kg m^2)
    state: dict[str, float] = field(default_factory=dict)
    propulsion: bool = False  # True: aerodynamic + propulsive (total) derivatives

    def __getitem__(self, name: str) -> float:
        if name in self.values:
            return self.values[name]
        if name in self.flags:
            k = self.flags[name]
            raise KeyError(f"{name} has a kink at trim: slopes {k.minus:.4g} / {k.plus:.4g}")
        raise KeyError(f"no truth derivative {name!r}; have {', '.join(sorted(self.values))}")

    def __str__(self) -> str:
        """The nonzero derivatives, one per line, then the kinks."""
        head = (f"{self.aircraft} at {self.trim.altitude_m:g} m, {self.trim.speed_m_s:g} m/s, "
                f"{self.axes} axes{' (aero + propulsion)' if self.propulsion else ''}")
        lines = [f"  {n:<14}{v:>11.5g}" for n, v in sorted(self.values.items()) if v != 0.0]
        kinks = [f"  {n:<14}kink: {k.minus:.4g} / {k.plus:.4g}"
                 for n, k in sorted(self.flags.items())]
        return "\n".join([head, *lines, *kinks])

    def to_json_dict(self) -> dict[str, Any]:
        """Flat {name: value} plus 'trim', 'axes' and 'flags' (for the CLI's JSON)."""
        out: dict[str, Any] = dict(sorted(self.values.items()))
        out["axes"] = self.axes
        out["propulsion"] = self.propulsion
        out["trim"] = {
            "alpha": self.trim.alpha, "theta": self.trim.theta, "elevator": self.trim.elevator,
            "aileron": self.trim.aileron, "rudder": self.trim.rudder,
            "throttle": self.trim.throttle, "altitude_m": self.trim.altitude_m,
            "speed_m_s": self.trim.speed_m_s,
        }
        out["flags"] = {n: {"minus": k.minus, "plus": k.plus, "central": k.central,
                            "note": k.note} for n, k in sorted(self.flags.items())}
        return out


# -- evaluation at a set state -------------------------------------------------------

class _Evaluator:
    """Evaluates the aerodynamic coefficients at trim plus perturbations (run_ic, dt = 0)."""

    def __init__(self, model: Model, trim: Trim, propulsion: bool = False) -> None:
        self.model = model
        self.trim = trim
        self.propulsion = propulsion
        fdm = model.fdm
        apply(model, trim)
        self.V = fdm["velocities/vt-fps"]
        self.b = fdm["metrics/bw-ft"]
        self.c = fdm["metrics/cbarw-ft"]
        self.alpha0 = fdm["aero/alpha-rad"]
        self.beta0 = fdm["aero/beta-rad"]
        self.commands = {k: v for k, v in trim.jsbsim.items() if not k.startswith("ic/")}

    def __call__(self, *, alpha: float = 0.0, beta: float = 0.0, p: float = 0.0,
                 q: float = 0.0, r: float = 0.0, theta: float = 0.0,
                 command: tuple[str, float] | None = None) -> np.ndarray:
        """[CX CY CZ Cl Cm Cn CL CD | alpha beta phat qhat rhat adothat de da dr]."""
        fdm, t = self.model.fdm, self.trim.jsbsim
        for prop, value in self.commands.items():
            fdm[prop] = value
        if command is not None:
            fdm[command[0]] = self.commands[command[0]] + command[1]
        a, bt = self.alpha0 + alpha, self.beta0 + beta
        for prop in ("ic/h-sl-ft", "ic/terrain-elevation-ft", "ic/lat-geod-deg",
                     "ic/long-gc-deg", "ic/phi-rad", "ic/psi-true-rad"):
            fdm[prop] = t[prop]
        fdm["ic/theta-rad"] = t["ic/theta-rad"] + theta
        fdm["ic/u-fps"] = self.V * math.cos(a) * math.cos(bt)
        fdm["ic/v-fps"] = self.V * math.sin(bt)
        fdm["ic/w-fps"] = self.V * math.sin(a) * math.cos(bt)
        k_lat, k_lon = 2 * self.V / self.b, 2 * self.V / self.c
        fdm["ic/p-rad_sec"] = t["ic/p-rad_sec"] + p * k_lat
        fdm["ic/q-rad_sec"] = t["ic/q-rad_sec"] + q * k_lon
        fdm["ic/r-rad_sec"] = t["ic/r-rad_sec"] + r * k_lat
        fdm.set_trim_status(True)
        try:
            fdm.run_ic()
        finally:
            fdm.set_trim_status(False)
        m = self.model
        coef = coefficients(m, self.propulsion)
        V = fdm["velocities/vt-fps"]
        return np.array([
            coef["CX"], coef["CY"], coef["CZ"], coef["Cl"], coef["Cm"], coef["Cn"],
            coef["CL"], coef["CD"],
            fdm["aero/alpha-rad"], fdm["aero/beta-rad"],
            fdm["velocities/p-aero-rad_sec"] * self.b / (2 * V),
            fdm["velocities/q-aero-rad_sec"] * self.c / (2 * V),
            fdm["velocities/r-aero-rad_sec"] * self.b / (2 * V),
            fdm["aero/alphadot-rad_sec"] * self.c / (2 * V),
            m.surface("de"), m.surface("da"), m.surface("dr"),
        ])


_NC = 8  # number of coefficients in an evaluation vector
_VAR_INDEX = {"alpha": 8, "beta": 9, "p": 10, "q": 11, "r": 12, "alphadot": 13,
              "de": 14, "da": 15, "dr": 16}


def _slopes(ev: _Evaluator, var: str, h: float, c_adot: np.ndarray,
            base: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(minus, plus, central) slopes of the 8 coefficients w.r.t. var at step h."""
    if var in COMMANDS:
        cmd = COMMANDS[var][0]
        plus, minus = ev(command=(cmd, h)), ev(command=(cmd, -h))
    else:
        plus, minus = ev(**{var: h}), ev(**{var: -h})
    i = _VAR_INDEX[var]
    iad = _VAR_INDEX["alphadot"]

    def corrected(x: np.ndarray) -> np.ndarray:
        return x[:_NC] - c_adot * (x[iad] - base[iad])

    dp, dm = plus[i] - base[i], minus[i] - base[i]
    if abs(dp) < 1e-12 or abs(dm) < 1e-12:
        raise ValueError(f"{ev.model.name}: perturbing {var} does not move it (saturated?)")
    s_plus = (corrected(plus) - base[:_NC]) / dp
    s_minus = (corrected(minus) - base[:_NC]) / dm
    central = (corrected(plus) - corrected(minus)) / (dp - dm)
    return s_minus, s_plus, central


def _alphadot_slope(ev: _Evaluator, base: np.ndarray) -> tuple[np.ndarray, float]:
    """dC/d(alphadot_hat) from pitch-attitude changes (gravity changes wdot, nothing else)."""
    iad = _VAR_INDEX["alphadot"]
    slopes = []
    for dtheta in (math.radians(25), math.radians(50)):
        x = ev(theta=dtheta)
        slopes.append((x[:_NC] - base[:_NC]) / (x[iad] - base[iad]))
    return slopes[1], float(np.max(np.abs(slopes[1] - slopes[0])))


def _engine_slope(ev: _Evaluator, base: np.ndarray, h: float) -> np.ndarray | None:
    """dC/d(throttle) with the engines at steady state at throttle +- h, or None."""
    m = ev.model
    props = [p for p in m.throttle_props() if m.has(p)]
    out = []
    for sign in (1.0, -1.0):
        for p in props:
            m.fdm[p] = ev.commands[p] + sign * h
        m.fdm.get_propulsion().get_steady_state()
        for p in props:
            ev.commands[p] += sign * h
        out.append(ev())
        for p in props:
            ev.commands[p] -= sign * h
    for p in props:
        m.fdm[p] = ev.commands[p]
    m.fdm.get_propulsion().get_steady_state()
    return (out[0][:_NC] - out[1][:_NC]) / (2 * h)


def _aero_uses_throttle(model: Model) -> bool:
    text = model.xml_path.read_text(encoding="utf-8", errors="replace")
    start = text.find("<aerodynamics")
    aero = text[start:] if start >= 0 else ""
    return "throttle" in aero or "thrust" in aero


def derivatives(model: Model | str, trim: Trim, axes: str = "body",
                steps: dict[str, float] | None = None, propulsion: bool = False) -> Truth:
    """Truth derivatives (per rad, per unit nondimensional rate) at a trim point.

    Parameters
    ----------
    model : Model or str
        The loaded JSBSim model, or an aircraft name; a copy is used.
    trim : Trim
        The trim point, for the same aircraft.
    axes : str, optional
        "body" (default; CX CY CZ Cl Cm Cn, body rates) or "stability" (CL CD CY Cl Cm Cn
        and rates rotated by the trim alpha); CL and CD are given in both.
    steps : dict of str to float, optional
        Finite-difference steps by variable, overriding ``STEPS`` (rad, or nondimensional
        rate).
    propulsion : bool, optional
        Differentiate aerodynamic + propulsive forces and moments with the engines at their
        trim state (the total derivatives a flight test sees); default False (aerodynamic
        only).

    Returns
    -------
    Truth
        Values by canonical name, kink flags, step spreads and the trim state (SI).

    Raises
    ------
    ValueError
        For unknown axes or a trim of another aircraft.
    """
    if axes not in ("body", "stability"):
        raise ValueError(f"axes must be 'body' or 'stability', got {axes!r}")
    model = as_model(model)
    if trim.aircraft != model.name:
        raise ValueError(f"trim is for {trim.aircraft!r}, model is {model.name!r}")
    # a fresh copy: the result depends on (aircraft, trim) only, not on the model's history
    model = model.copy()
    steps = {**STEPS, **(steps or {})}
    ev = _Evaluator(model, trim, propulsion)
    base = ev()
    c_adot = np.zeros(_NC)
    # per variable: (central, minus, plus, kink mask, step spread), 8-vectors
    found: dict[str, tuple[np.ndarray, ...]] = {}
    if model.uses_alphadot:
        c_adot, adot_spread = _alphadot_slope(ev, base)
        none = np.zeros(_NC, bool)
        found["alphadot"] = (c_adot, c_adot, c_adot, none, np.full(_NC, adot_spread))
    for var in ("alpha", "beta", "p", "q", "r", "de", "da", "dr"):
        if var in COMMANDS and not model.has(COMMANDS[var][0]):
            continue
        h = steps[var]
        m1, p1, c1 = _slopes(ev, var, h, c_adot, base)
        m2, p2, c2 = _slopes(ev, var, h / 4, c_adot, base)
        gap_small, gap_big = np.abs(p2 - m2), np.abs(p1 - m1)
        tol = KINK_ABS + KINK_REL * np.maximum(np.abs(p2), np.abs(m2))
        kink = (gap_small > tol) & (gap_small > _SHRINK * gap_big)
        found[var] = (c2, m2, p2, kink, np.abs(c1 - c2))
    if _aero_uses_throttle(model) and model.n_engines:
        dt = _engine_slope(ev, base, steps["dt"])
        found["dt"] = (dt, dt, dt, np.zeros(_NC, bool), np.zeros(_NC))
    ev()  # leave the model at the trim state
    truth = _assemble(model, trim, axes, base, found)
    truth.propulsion = propulsion
    return truth


def _assemble(model: Model, trim: Trim, axes: str, base: np.ndarray,
              found: dict[str, tuple[np.ndarray, ...]]) -> Truth:
    ca, sa = math.cos(trim.alpha), math.sin(trim.alpha)

    def rows(vec: np.ndarray) -> dict[str, float]:
        """Coefficient letter -> value in the requested axes (Cl, Cn rotated by trim alpha)."""
        cx, cy, cz, cl, cm, cn, lift, drag = (float(x) for x in vec)
        if axes == "body":
            return {"X": cx, "Y": cy, "Z": cz, "l": cl, "m": cm, "n": cn, "L": lift, "D": drag}
        return {"L": lift, "D": drag, "Y": cy, "l": cl * ca + cn * sa, "m": cm,
                "n": cn * ca - cl * sa}

    def kinked(mask: np.ndarray) -> set[str]:
        m = mask.astype(float)
        if axes == "stability":  # a kink in Cl or Cn spoils both rotated moments
            m[3] = m[5] = max(m[3], m[5])
        return {c for c, flag in rows(m).items() if flag > 0}

    per_var = dict(found)
    if axes == "stability" and "p" in found and "r" in found:
        # d/dp_s = cos a d/dp + sin a d/dr ; d/dr_s = -sin a d/dp + cos a d/dr
        fp, fr = found["p"], found["r"]
        mask = fp[3] | fr[3]
        per_var["p"] = tuple(ca * x + sa * y for x, y in zip(fp[:3], fr[:3], strict=True)) + (
            mask, np.abs(ca) * fp[4] + np.abs(sa) * fr[4])
        per_var["r"] = tuple(-sa * x + ca * y for x, y in zip(fp[:3], fr[:3], strict=True)) + (
            mask, np.abs(sa) * fp[4] + np.abs(ca) * fr[4])
    values = {f"C{coef}_0": v for coef, v in rows(base[:_NC]).items()}
    flags: dict[str, Kink] = {}
    spreads: dict[str, float] = {}
    for var, (central, minus, plus, mask, spread) in per_var.items():
        bad = kinked(mask)
        c_rows, m_rows, p_rows, s_rows = rows(central), rows(minus), rows(plus), rows(spread)
        for coef, value in c_rows.items():
            name = f"C{coef}_{var}"
            if coef in bad:
                flags[name] = Kink(m_rows[coef], p_rows[coef], value,
                                   f"one-sided slopes in {var} differ at trim (kink)")
            else:
                # differences of 1e-16 coefficients over 1e-3 steps: below 1e-10 is roundoff
                values[name] = value if abs(value) > ZERO else 0.0
                spreads[name] = abs(s_rows[coef])
    g = model.get
    # structural frame (x aft, y right, z up) -> body axes (x forward, y right, z down)
    cg_rp = (-(g("inertia/cg-x-in") - g("metrics/aero-rp-x-in")) * 0.0254,
             (g("inertia/cg-y-in") - g("metrics/aero-rp-y-in")) * 0.0254,
             -(g("inertia/cg-z-in") - g("metrics/aero-rp-z-in")) * 0.0254)
    state = {
        "qbar": g("aero/qbar-psf") * PSF, "V": g("velocities/vt-fps") * FT,
        "mass": g("inertia/mass-slugs") * SLUG,
        "Ixx": g("inertia/ixx-slugs_ft2") * SLUG_FT2, "Iyy": g("inertia/iyy-slugs_ft2") * SLUG_FT2,
        "Izz": g("inertia/izz-slugs_ft2") * SLUG_FT2,
        "Ixz": -g("inertia/ixz-slugs_ft2") * SLUG_FT2,  # Etkin's sign (JSBSim gives -Ixz)
    }
    return Truth(aircraft=model.name, axes=axes, trim=trim, reference=model.reference,
                 values=values, flags=flags, step_spread=spreads, cg_minus_aerorp_m=cg_rp,
                 state=state)


# -- JSBSim's own linearization --------------------------------------------------------

def linearization(model: Model | str, trim: Trim) -> StateSpace:
    """JSBSim's FGLinearization (A, B) at the trim point, in JSBSim's state units.

    Parameters
    ----------
    model : Model or str
        The loaded JSBSim model, or an aircraft name; a copy is used.
    trim : Trim
        The trim point.

    Returns
    -------
    StateSpace
        A, B and the names and units of states and inputs.
    """
    model = as_model(model).copy()
    apply(model, trim)
    lin = jsbsim.FGLinearization(model.fdm)
    return StateSpace(
        A=np.array(lin.system_matrix), B=np.array(lin.input_matrix),
        x_names=tuple(lin.x_names), u_names=tuple(lin.u_names),
        x_units=tuple(lin.x_units), u_units=tuple(lin.u_units),
    )


def pitch_entries(truth: Truth) -> dict[str, float]:
    """Short-period A entries predicted from the body-axis derivatives.

    qdot = M_alpha alpha + M_q q + M_alphadot alphadot (Etkin & Reid, ch. 4), with
    M_x = qbar S cbar Cm_x / Iyy and the rate derivatives scaled by cbar / 2V.

    Parameters
    ----------
    truth : Truth
        Body-axis truth derivatives with the trim state.

    Returns
    -------
    dict of str to float
        M_alpha (1/s^2), M_q and M_alphadot (1/s).
    """
    st, ref, v = truth.state, truth.reference, truth.values
    qsc = st["qbar"] * ref.area * ref.chord
    k = ref.chord / (2 * st["V"])
    return {
        "M_alpha": qsc * v["Cm_alpha"] / st["Iyy"],
        "M_q": qsc * v["Cm_q"] * k / st["Iyy"],
        "M_alphadot": qsc * v.get("Cm_alphadot", 0.0) * k / st["Iyy"],
    }
