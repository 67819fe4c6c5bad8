"""Refit without the parameters the flight cannot determine.

A parameter with no effect on the outputs, or one that moves them only in combination
with others, makes the information matrix singular: the Newton steps are then undefined
and the Cramer-Rao bounds infinite. Such a parameter is fixed at its a priori value and
the others are refitted (Morelli & Klein 2016, sec. 6.3; Jategaonkar 2015, sec. 4.17).
``refit_without_unidentifiable`` is that loop for every method; the method supplies how
to fit and how to find the unidentifiable parameters (usually
``identifiability.unidentifiable`` on the fit's information matrix).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Protocol, TypeVar


class Fit(Protocol):
    """What the loop needs of a fit: the values of its active parameters."""

    @property
    def values(self) -> Mapping[str, float]: ...


F = TypeVar("F", bound=Fit)


def refit_without_unidentifiable(
    names: Sequence[str],
    start: Mapping[str, float],
    fit: Callable[[list[str], dict[str, float]], F],
    unidentifiable: Callable[[list[str], F], Mapping[str, str]],
    *,
    probe: Callable[[list[str], dict[str, float]], F] | None = None,
    known: Mapping[str, str] | None = None,
) -> tuple[F, dict[str, str]]:
    """Fit, find the unidentifiable parameters, fix them, refit.

    After a pass that finds some, the values of the rest become the start of the next.

    Parameters
    ----------
    names : sequence of str
        The parameters to estimate.
    start : mapping of str to float
        The value of each (a priori, parameter units), with any other parameter the fit may
        read.
    fit : callable
        ``fit(active, values)`` fits the ``active`` parameters starting from ``values`` (every
        parameter's current value: the fixed ones at their a priori values, unless an earlier
        pass moved them).
    unidentifiable : callable
        ``unidentifiable(active, fit)`` returns {name: reason} of those the fit cannot
        determine (empty to accept it).
    probe : callable, optional
        ``probe(active, values)``, evaluated first at the start values of each pass (an
        iteration-free fit), so that the iteration never meets a singular information matrix.
    known : mapping of str to str, optional
        Parameters already found unidentifiable (unexcited inputs): never active, and
        returned with the others.

    Returns
    -------
    tuple of (fit, dict of str to str)
        The last fit and {name: reason} of every parameter fixed.
    """
    found_all = dict(known or {})
    values = dict(start)
    for _ in range(len(names) + 1):
        active = [n for n in names if n not in found_all]
        if probe is not None:
            found = unidentifiable(active, probe(active, dict(values)))
            if found:
                found_all.update(found)
                continue
        result = fit(active, dict(values))
        found = unidentifiable(active, result)
        if not found:
            break
        found_all.update(found)
        values.update(result.values)
    return result, found_all


def refit_iterated(
    names: Sequence[str],
    start: Mapping[str, float],
    fit: Callable[[list[str], dict[str, float], int], F],
    singular: Callable[[list[str], F], Mapping[str, str]],
    *,
    check_identifiability: bool = True,
    known: Mapping[str, str] | None = None,
) -> tuple[F, dict[str, str]]:
    """``refit_without_unidentifiable`` for an iterative fit.

    With ``check_identifiability`` each pass is first probed at its start values with zero
    iterations, so the iteration never meets a singular information matrix, and ``singular``
    judges the fits; without it the first fit is accepted.

    Parameters
    ----------
    names : sequence of str
        The parameters to estimate.
    start : mapping of str to float
        The start values, parameter units.
    fit : callable
        ``fit(active, values, iterations)``.
    singular : callable
        ``singular(active, fit)`` returns {name: reason} of those the fit cannot determine.
    check_identifiability : bool, optional
        Probe and judge each pass. Default True.
    known : mapping of str to str, optional
        Parameters already found unidentifiable.

    Returns
    -------
    tuple of (fit, dict of str to str)
        The last fit and {name: reason} of every parameter fixed.
    """
    if not check_identifiability:
        return refit_without_unidentifiable(names, start, fit, lambda active, f: {},
                                            known=known)
    return refit_without_unidentifiable(
        names, start, fit, singular, probe=lambda active, values: fit(active, values, 0),
        known=known)
