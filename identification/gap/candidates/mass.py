"""Mass-property entries of the catalogue as candidates of the linear model.

- ``cg_offset`` (x, m forward): the moments taken about a CG moved forward by x see the
  aerodynamic forces with an arm, Cm' = Cm - CL x/cbar and Cn' = Cn - CY x/b (Etkin &
  Reid 1996 §2.3: Cm_alpha = CL_alpha (h - h_n)): every Cm derivative falls by its lift
  derivative times x/cbar, every Cn derivative by its side-force derivative times x/b.
  Its z is held at 0 (a vertical shift acts through the small CX and CD terms). Against a
  Cm_alpha delta (longitudinal) or a Cn_beta delta (lateral) it differs only through the
  smaller control and rate terms: one equivalence class (docs/gap.md);
- ``mass_scale`` (factor): the aerodynamic accelerations per unit coefficient fall as
  1/m: every force derivative (CY_*, CL_*, CD_* but the trim terms CL_0 and CD_0, which
  the heavier trim raises by the same factor) and the thrust input are divided by it;
- ``inertia_scale`` (ixx or izz on the lateral axis, a candidate each; iyy on the
  longitudinal): the reference condition's inertia scaled (Ixz by sqrt(ixx izz), as the
  catalogue injects it); the angular accelerations are I^-1 M, with M the model's
  moments. An Izz scale and a scaling of every Cn term are one equivalence class;
- ``thrust_moment`` (arm, m): qdot gets arm dT/Iyy, on a longitudinal model whose
  thrust is an input (``linearise``: records with the measured thrust).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from flightid.identification.gap.model.edits import Candidate, extended
from flightid.identification.models.linear import LinearModel

_MOMENT = {"Cm": ("CL", "chord"), "Cn": ("CY", "span")}  # moment <- force, length


def _moved(model: LinearModel) -> list[tuple[str, str, float]]:
    """(moment derivative, force derivative, length) pairs the CG arm couples."""
    c = model.condition
    out = []
    for d in model.parameters:
        coef, _, var = d.partition("_")
        if coef in _MOMENT and var and var != "0":
            force, length = _MOMENT[coef]
            out.append((d, f"{force}_{var}", getattr(c, length)))
    return out


def cg_offset(model: LinearModel) -> Candidate | None:
    """The CG moved forward by x (m).

    Parameters
    ----------
    model : LinearModel
        The linearised aircraft of one axis.

    Returns
    -------
    Candidate or None
        None without a reference condition or any moment derivative a CG shift moves.
    """
    if model.condition is None:
        return None
    pairs = [(m, f, length) for m, f, length in _moved(model) if f in model.parameters]
    if not pairs:
        return None
    name = "cg_x"

    def wrap(m: LinearModel) -> LinearModel:
        def build(v: Mapping[str, complex]) -> tuple:
            w = dict(v)
            for moment, force, length in pairs:
                w[moment] = v[moment] - v[force] * v[name] / length
            return m.build(w)

        return extended(m, {name: 0.0}, build)

    return Candidate("cg_offset", {}, (name,), wrap, catalogue=("x",))


FORCES = ("CY", "CL", "CD")
TRIM = ("CL_0", "CD_0")


def mass_scale(model: LinearModel) -> Candidate | None:
    """The mass scaled by ``factor``.

    Parameters
    ----------
    model : LinearModel
        The linearised aircraft of one axis.

    Returns
    -------
    Candidate or None
        None when the model has no force derivative (trim terms aside).
    """
    scaled = [d for d in model.parameters
              if d.partition("_")[0] in FORCES and d not in TRIM]
    if not scaled:
        return None
    name = "mass_factor"

    def wrap(m: LinearModel) -> LinearModel:
        thrust = m.inputs.index("thrust") if "thrust" in m.inputs else None

        def build(v: Mapping[str, complex]) -> tuple:
            w = dict(v)
            for d in scaled:
                w[d] = v[d] / v[name]
            A, B, C, D = m.build(w)
            if thrust is not None:
                B = B.astype(np.result_type(B.dtype, type(v[name])))
                B[:, thrust] = B[:, thrust] / v[name]
            return A, B, C, D

        return extended(m, {name: 1.0}, build)

    return Candidate("mass_scale", {}, (name,), wrap)


def inertia_scales(model: LinearModel) -> list[Candidate]:
    """The inertias of the model's axis scaled, one candidate per inertia (ixx and izz
    lateral, iyy longitudinal): a candidate freeing both lateral inertias would lose every
    tie to a one-parameter derivative delta (``rank.simplest``) where only one is off.

    Parameters
    ----------
    model : LinearModel
        The linearised aircraft of one axis.

    Returns
    -------
    list of Candidate
        Empty without a reference condition or a p, r or q state.
    """
    c = model.condition
    if c is None:
        return []
    if {"p", "r"} <= set(model.states):
        names = ("inertia_ixx", "inertia_izz")
        rows = ("p", "r")
        inertia = np.array([[c.Ixx, -c.Ixz], [-c.Ixz, c.Izz]])
    elif "q" in model.states:
        names, rows, inertia = ("inertia_iyy",), ("q",), np.array([[c.Iyy]])
    else:
        return []

    def scaled(name: str) -> Candidate:
        def wrap(m: LinearModel) -> LinearModel:
            idx = [m.states.index(s) for s in rows]
            inv = np.linalg.inv(inertia)

            def build(v: Mapping[str, complex]) -> tuple:
                A, B, C, D = m.build(v)
                # a non-positive trial factor (no physical inertia) gives NaN, which the
                # fit rejects
                with np.errstate(invalid="ignore"):
                    root = np.array([np.sqrt(v[n]) if n == name else 1.0 for n in names])
                # I' = S I S with S = diag(sqrt(factor)): I'^-1 I = S^-1 I^-1 S^-1 I
                change = (inv / np.outer(root, root)) @ inertia
                dtype = np.result_type(A.dtype, change.dtype)
                A, B = A.astype(dtype), B.astype(dtype)
                A[idx], B[idx] = change @ A[idx], change @ B[idx]
                return A, B, C, D

            return extended(m, {name: 1.0}, build)

        return Candidate("inertia_scale", {}, (name,), wrap,
                         catalogue=(name.removeprefix("inertia_"),))

    return [scaled(n) for n in names]


def thrust_moment(model: LinearModel) -> Candidate | None:
    """A pitching moment arm x thrust (m), when thrust is an input of the model.

    Parameters
    ----------
    model : LinearModel
        The linearised aircraft of one axis.

    Returns
    -------
    Candidate or None
        None without a reference condition, a thrust input or a q state.
    """
    c = model.condition
    if c is None or "thrust" not in model.inputs or "q" not in model.states:
        return None
    name = "thrust_arm"

    def wrap(m: LinearModel) -> LinearModel:
        row, col = m.states.index("q"), m.inputs.index("thrust")

        def build(v: Mapping[str, complex]) -> tuple:
            A, B, C, D = m.build(v)
            B = B.astype(np.result_type(B.dtype, type(v[name])))
            B[row, col] = B[row, col] + v[name] / c.Iyy
            return A, B, C, D

        return extended(m, {name: 0.0}, build)

    return Candidate("thrust_moment", {}, (name,), wrap, catalogue=("arm",))


def mass_candidates(model: LinearModel) -> list[Candidate]:
    """Every mass-property candidate for ``model``.

    Parameters
    ----------
    model : LinearModel
        The linearised aircraft of one axis.

    Returns
    -------
    list of Candidate
        Those that apply to the model.
    """
    return [*(c for f in (cg_offset, mass_scale, thrust_moment) if (c := f(model)) is not None),
            *inertia_scales(model)]
