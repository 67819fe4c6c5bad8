"""Force and moment coefficients of the current JSBSim state (no propagation).

Shared by the trim (stall and power checks read CL and CD) and the truth derivatives
(which difference them): it lives below both so that ``trim`` and ``truth`` do not import
each other. Body axes about the CG, lift and drag in the local stability axes:
CL = CX sin a - CZ cos a, CD = -CX cos a - CZ sin a.
"""

from __future__ import annotations

import math

from flightid.sim.jsbsim.model import Model


def coefficients(model: Model, propulsion: bool = False) -> dict[str, float]:
    """Force and moment coefficients of the current JSBSim state.

    Parameters
    ----------
    model : Model
        The loaded JSBSim model, at the state to evaluate.
    propulsion : bool, optional
        Aerodynamic + propulsive forces and moments; default False (aerodynamic only).

    Returns
    -------
    dict of str to float
        CX CY CZ Cl Cm Cn (body axes, about the CG), CL CD; dimensionless.
    """
    g = model.get
    qs = g("aero/qbar-psf") * g("metrics/Sw-sqft")
    b, c = g("metrics/bw-ft"), g("metrics/cbarw-ft")
    sources = ("aero", "prop") if propulsion else ("aero",)

    def total(prop: str) -> float:
        return sum(g(prop.format(src)) for src in sources)

    cx = total("forces/fbx-{}-lbs") / qs
    cy = total("forces/fby-{}-lbs") / qs
    cz = total("forces/fbz-{}-lbs") / qs
    a = g("aero/alpha-rad")
    return {
        "CX": cx, "CY": cy, "CZ": cz,
        "Cl": total("moments/l-{}-lbsft") / (qs * b),
        "Cm": total("moments/m-{}-lbsft") / (qs * c),
        "Cn": total("moments/n-{}-lbsft") / (qs * b),
        "CL": cx * math.sin(a) - cz * math.cos(a),
        "CD": -cx * math.cos(a) - cz * math.sin(a),
    }
