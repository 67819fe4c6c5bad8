"""Terms of the model itself that a left-right symmetric airframe cannot have.

A symmetric aircraft's side force, rolling and yawing moment are odd functions of the
lateral motion variables sideslip, roll rate and yaw rate (Etkin & Reid 1996, sec. 4.3:
reflected in the plane of symmetry, the motion and these three change sign). A model whose
one-sided slopes in one of them differ at the trim (``truth.Kink``; the stock JSBSim DHC6's
``Clb`` table gives Cl = +0.036 at beta = +5 deg and at -5 deg) carries a term even in
that variable, ``(plus - minus) / 2 * abs(variable)``. Its linearisation holds the mean
slope, so the linear diagnosis cannot see the even term, while the JSBSim aircraft flies
with it. Each such term is reported, and written out of the corrected aircraft
(``straightening``), so that the aircraft flown again is the model the diagnosis tested.
"""

from __future__ import annotations

from dataclasses import dataclass

from flightid.sim.effects.airframe import DerivativeDelta
from flightid.sim.jsbsim.truth import Kink

ODD_IN = ("beta", "p", "r")  # the variables a symmetric airframe's CY, Cl, Cn are odd in
LATERAL_COEFFICIENTS = ("CY", "Cl", "Cn")


@dataclass(frozen=True)
class EvenTerm:
    """A lateral derivative with different one-sided slopes (per rad, or per unit
    nondimensional rate) at the trim, in the diagnosis's axes."""

    derivative: str
    minus: float  # slope for the variable below its trim value
    plus: float  # above it
    axes: str

    @property
    def even(self) -> float:
        """The even term's coefficient: C = ... + even * abs(variable)."""
        return 0.5 * (self.plus - self.minus)

    @property
    def odd(self) -> float:
        """The mean slope: the derivative the linearisation uses."""
        return 0.5 * (self.plus + self.minus)

    def text(self) -> str:
        """One line for the report."""
        var = self.derivative.split("_", 1)[1]
        return (f"{self.derivative}: the model's slope is {self.minus:+.3g} for {var} < 0 "
                f"and {self.plus:+.3g} for {var} > 0 ({self.axes} axes): a term "
                f"{self.even:+.3g} abs({var}), even in {var}, which a left-right symmetric "
                f"airframe cannot have; the linearised model uses the mean {self.odd:+.3g}")

    def straightening(self) -> DerivativeDelta:
        """The airframe effect that removes the even term from the aircraft."""
        return DerivativeDelta(delta=-self.even, derivative=self.derivative, axes=self.axes,
                               form="even", source="flightid gap: even term removed")


def even_terms(kinks: dict[str, Kink], axes: str) -> list[EvenTerm]:
    """The kinks of ``kinks`` (derivative -> ``Kink``) that break the airframe's symmetry:
    CY, Cl or Cn in beta, p or r.

    Parameters
    ----------
    kinks : dict of str to Kink
        The model's kinks at trim (``Linearised.kinks``).
    axes : str
        Their axes.

    Returns
    -------
    list of EvenTerm
    """
    out = []
    for name, k in sorted(kinks.items()):
        coef, _, var = name.partition("_")
        if coef in LATERAL_COEFFICIENTS and var in ODD_IN:
            out.append(EvenTerm(name, k.minus, k.plus, axes))
    return out
