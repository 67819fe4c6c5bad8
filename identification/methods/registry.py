"""Every identification method, registered once by its id.

The built-in methods are listed here; other packages add theirs through the entry-point
group ``flightid.methods`` (an entry point names a ``Method`` value), e.g. in their
pyproject.toml::

    [project.entry-points."flightid.methods"]
    mymethod = "mypackage.mymethod:METHOD"
"""

from __future__ import annotations

from importlib.metadata import entry_points

from flightid.identification.methods import (
    equation_error,
    filter_error,
    frequency_equation_error,
    frequency_output_error,
    frequency_response_fit,
    mof,
    nonlinear_6dof,
    output_error,
    stepwise,
)
from flightid.identification.methods.protocol import Method
from flightid.identification.models import structure as model_structure

ENTRY_POINT_GROUP = "flightid.methods"
BUILTIN: tuple[Method, ...] = (
    equation_error.METHOD, stepwise.METHOD, output_error.METHOD, nonlinear_6dof.METHOD,
    filter_error.METHOD, frequency_equation_error.METHOD, frequency_output_error.METHOD,
    frequency_response_fit.METHOD, mof.METHOD,
)
_REGISTRY: dict[str, Method] = {m.id: m for m in BUILTIN}
_loaded_entry_points = False


def register(method: Method) -> Method:
    """Add a method under its id (a second method with the same id is refused).

    Parameters
    ----------
    method : Method
        The method to add.

    Returns
    -------
    Method
        ``method`` itself.

    Raises
    ------
    TypeError
        ``method`` is not a Method.
    ValueError
        Another method already has its id.
    """
    if not isinstance(method, Method):
        raise TypeError(f"register takes a Method, got {type(method).__name__}")
    known = _REGISTRY.get(method.id)
    if known is not None and known is not method:
        raise ValueError(f"a method with id {method.id!r} is already registered "
                         f"({known.name})")
    _REGISTRY[method.id] = method
    return method


def unregister(method_id: str) -> None:
    """Remove a method added by ``register`` (built-in methods stay).

    Parameters
    ----------
    method_id : str
        Id of the method; an id not registered is ignored.

    Raises
    ------
    ValueError
        ``method_id`` is a built-in method.
    """
    if any(m.id == method_id for m in BUILTIN):
        raise ValueError(f"{method_id!r} is a built-in method")
    _REGISTRY.pop(method_id, None)


def load_entry_points() -> list[str]:
    """Register the methods of every installed ``flightid.methods`` entry point.

    Call it again after installing a plug-in.

    Returns
    -------
    list of str
        The ids found.

    Raises
    ------
    ValueError
        An entry point fails to load (naming it), or its id is taken.
    """
    global _loaded_entry_points
    _loaded_entry_points = True
    found = []
    for ep in entry_points(group=ENTRY_POINT_GROUP):
        try:
            method = ep.load()
        except Exception as exc:  # name the plug-in, not a bare traceback
            raise ValueError(f"entry point {ep.name!r} of group {ENTRY_POINT_GROUP} "
                             f"({ep.value}) failed to load: {exc}") from exc
        register(method)
        found.append(method.id)
    return found


def methods() -> dict[str, Method]:
    """{id: Method} of every method: built-in, registered, and from entry points.

    Returns
    -------
    dict of str to Method
        A copy of the registry; entry points are loaded on the first call.
    """
    if not _loaded_entry_points:
        load_entry_points()
    return dict(_REGISTRY)


def get(method_id: str) -> Method:
    """The method with this id.

    Parameters
    ----------
    method_id : str
        The method id (``--method``).

    Returns
    -------
    Method
        The registered method.

    Raises
    ------
    ValueError
        The id is unknown; the message lists the valid ids.
    """
    found = methods()
    if method_id not in found:
        raise ValueError(f"unknown method {method_id!r}; known: {', '.join(found)}")
    return found[method_id]


def check_model(method_id: str, model: str) -> str:
    """``model`` in its canonical spelling if method ``method_id`` takes it.

    Parameters
    ----------
    method_id : str
        The method id.
    model : str
        A preset, its alias, 'auto', or for the regression methods a structure
        'Coef=term+term; ...'.

    Returns
    -------
    str
        The canonical model name (or the structure text).

    Raises
    ------
    ValueError
        The method does not take the model (naming the models it takes), the method is
        unknown, or the structure is malformed.
    """
    spec = get(method_id)
    name = model_structure.canonical(str(model))
    if name == "auto" or name in spec.models and name != "structure":
        return name
    if "structure" in spec.models and "=" in name:
        model_structure.regression(name)  # a malformed structure: ValueError naming the part
        return name
    aliases = {v: k for k, v in model_structure.ALIASES.items()}
    accepted = [f"{m} ({aliases[m]})" if m in aliases else m
                for m in spec.models if m != "structure"]
    extra = " or a structure 'Coef=term+term; ...'" if "structure" in spec.models else ""
    raise ValueError(f"model {model!r} is not a model of method {spec.id}; use auto, "
                     f"{', '.join(accepted)}{extra}")
