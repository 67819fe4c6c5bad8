"""One rule for every iterative fit (oe, oe6dof, fem, fdoe, fr, the compatibility
reconstruction): an estimate that did not converge says so.

A method records ``fit['converged']`` (bool) and ``fit['reason']``; ``warn`` issues a
``NotConvergedWarning`` naming the method and the reason (the command line prints it and
puts "not converged" in the table's verdict line, exit 0), and ``require`` raises
``NotConvergedError`` instead (``--strict``; exit code 4 of docs/errors.md). Iteration
limits below 1 are refused by the option check (``check_limit``).
"""

from __future__ import annotations

import warnings

from flightid.identification.estimate import Estimate

NOT_CONVERGED = "not converged"


class NotConvergedWarning(UserWarning):
    """An iterative fit stopped before its convergence test passed."""


class NotConvergedError(RuntimeError):
    """An iterative fit did not converge and the caller asked for strictness."""


def converged(est: Estimate) -> bool:
    """False only when the estimate says it did not converge.

    Non-iterative methods record nothing and count as converged.

    Parameters
    ----------
    est : Estimate
        The estimate.

    Returns
    -------
    bool
        Whether ``est`` converged.
    """
    return est.fit.get("converged") is not False


def verdict_line(est: Estimate, what: str | None = None) -> str:
    """The not-converged line of an estimate, or '' when converged.

    For example 'oe: not converged (no convergence in 1 iterations): the values are not at the
    optimum and their std are not Cramer-Rao bounds; ...'.

    Parameters
    ----------
    est : Estimate
        The estimate.
    what : str, optional
        The line's subject. Default the estimate's method.

    Returns
    -------
    str
        The line, or ''.
    """
    if converged(est):
        return ""
    reason = est.fit.get("reason") or "the iteration limit was reached"
    return (f"{what or est.method}: {NOT_CONVERGED} ({reason}): the values are not at the "
            "optimum and their std are not Cramer-Rao bounds; raise max_iterations or "
            "check the model")


def warn(est: Estimate, what: str | None = None) -> None:
    """A NotConvergedWarning when ``est`` did not converge.

    Parameters
    ----------
    est : Estimate
        The estimate.
    what : str, optional
        The warning's subject. Default the estimate's method.
    """
    line = verdict_line(est, what)
    if line:
        warnings.warn(line, NotConvergedWarning, stacklevel=2)


def require(est: Estimate, what: str | None = None) -> None:
    """NotConvergedError when ``est`` did not converge (``--strict``).

    Parameters
    ----------
    est : Estimate
        The estimate.
    what : str, optional
        The error's subject. Default the estimate's method.

    Raises
    ------
    NotConvergedError
        When ``est`` did not converge.
    """
    line = verdict_line(est, what)
    if line:
        raise NotConvergedError(line)


def check_limit(method: str, name: str, value: object) -> None:
    """An iteration or relaxation limit (an option named ``max_*``) must be a whole number
    of at least 1.

    Parameters
    ----------
    method : str
        The method id, named in the error.
    name : str
        The option name.
    value : object
        The option's value; only an int is checked.

    Raises
    ------
    ValueError
        When ``value`` is an int below 1.
    """
    if isinstance(value, int) and not isinstance(value, bool) and value < 1:
        raise ValueError(f"option {name} of method {method} must be >= 1, got {value}")
