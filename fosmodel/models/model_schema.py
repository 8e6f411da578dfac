"""What a model file may hold: each field's type and range, each term inside the model's own spec.

:func:`check_model_dict` runs on the parsed JSON of a model file before anything is built from
it (:func:`fosmodel.models.model_file.load_model`, under both ``FOSModel.load`` and the
commands' :func:`fosmodel.io.model_file.read_model`), so that a damaged or forged file is refused in
one line naming the field, and never makes fosmodel allocate what it asks for (a lag of 10^12,
a power of 10^9) nor predict with what no fit gives: a term twice, more terms than candidates,
a weight that would scale the output's own spread a million times.

The checks are those a fitted :class:`~fosmodel.models.model.FOSModel` passes by construction:

* ``params`` are FOSModel's parameters, each of its type; the candidate set they define
  (counted, not built) is within ``max_candidates`` and :data:`MAX_CANDIDATES`, and a product
  has at most :data:`MAX_DEGREE` factors;
* ``fitted.terms`` are distinct members of that candidate set: output lags within ``max_lag``,
  input lags within ``exog_lags``, levels and columns among those offered, products of at
  most ``degree`` factors of the product factors, user columns alone; fewer than
  ``n_candidates``, which is the set's count;
* every number is finite (the standard errors may be NaN: a format 1 file has none) and at most
  :data:`MAX_ABS` in magnitude; ``mse_null`` (the training variance of the output) is positive,
  and the weight ``w`` of a term of the output alone (its lags and levels, ``d`` factors) is at
  most :data:`MAX_GAIN` once made dimensionless, ``|w| s^(d-1)`` with ``s = sqrt(mse_null)``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, NoReturn

from ..core.candidates import OUTPUT, Term
from ..core.exceptions import InputError
from ..core.fos import STOP_RULES
from ..core.levels import is_level, level_name
from .compensation import check_compensation

#: What a model file says it is, and the version of its format this fosmodel writes.
FORMAT = "fosmodel.FOSModel"
FORMAT_VERSION = 2
#: Fitted state a file of an older format version lacks, and what it reads as there:
#: version 1 carried no standard errors.
_ADDED_IN = {2: {"coef_se": lambda n_terms: [math.nan] * n_terms,
                 "intercept_se": lambda n_terms: math.nan}}

#: Candidates no fit searches (its correlation tables hold a row per candidate): a file asking
#: for more is refused before anything is counted or allocated for it.
MAX_CANDIDATES = 10**7
#: Factors of a product (Tamazin et al.'s (2013) cross-products have two or three).
MAX_DEGREE = 32
#: The largest magnitude of a number in a model file (the loader refuses larger values).
MAX_ABS = 1e30
#: The largest dimensionless weight of a term of the output alone, ``|w| s^(d-1)``: a stable
#: fit's lag weights are of order one, nearly dependent lags give tens or hundreds.
MAX_GAIN = 1e6
#: The longest text a model file may hold in a name (a term, a column, a stop reason).
MAX_NAME = 1000

_PARAMS = {  # FOSModel's parameters: how each is checked
    "center": "bool", "columns": "names", "compensation": "compensation",
    "correlations": "correlations", "degree": "degree",
    "dependence_tol": "fraction", "exog_lags": "lags", "levels": "taus",
    "max_candidates": "max_candidates", "max_lag": "lag", "max_terms": "count",
    "product_lags": "count", "rate": "rate", "stop": "stop", "tol": "tolerance",
}
_OPTIONAL = {"columns", "compensation", "exog_lags", "levels", "max_terms", "product_lags", "rate",
             "tol"}


def check_model_dict(data: object) -> Mapping[str, Any]:
    """Refuse a parsed model file that no fit could have written.

    Parameters
    ----------
    data : object
        The file's JSON value.

    Returns
    -------
    Mapping
        ``data``, checked.

    Raises
    ------
    InputError
        ``"not a fosmodel FOSModel file ..."``, a newer format, or ``"corrupted model file:
        FIELD: what is wrong"`` naming the first field that fails (``fitted.terms[3]``).
    """
    if not isinstance(data, Mapping) or data.get("format") != FORMAT:
        raise InputError("not a fosmodel FOSModel file (missing or wrong 'format')")
    version = data.get("format_version")
    if isinstance(version, bool) or not isinstance(version, int) or version < 1:
        _refuse("format_version", f"{_shown(version)} is not a format version")
    if version > FORMAT_VERSION:
        return data  # FOSModel.from_dict says which version this fosmodel reads
    params = _section(data, "params")
    fitted = _section(data, "fitted")
    _check_meta(data.get("meta") or {})
    _check_params(params)
    count = _candidate_count(params)
    _check_terms(fitted, params, count)
    _check_numbers(fitted, params, version)
    return data


def _refuse(field: str, problem: str) -> NoReturn:
    raise InputError(f"corrupted model file: {field}: {problem}")


def _shown(value: object) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _section(data: Mapping[str, Any], key: str) -> Mapping[str, Any]:
    value = data.get(key)
    if not isinstance(value, Mapping):
        _refuse(key, "missing" if value is None else "not an object")
    return value


def _check_meta(meta: object) -> None:
    """Refuse a ``meta`` that is no object, or whose column is no name (the rest is free)."""
    if not isinstance(meta, Mapping):
        _refuse("meta", "not an object")
    column = meta.get("column")
    if column is not None and (not isinstance(column, str) or not 0 < len(column) <= MAX_NAME):
        _refuse("meta.column", f"{_shown(column)} is not a column name")


# -- params ----------------------------------------------------------------------------------


def _check_params(params: Mapping[str, Any]) -> None:
    for key, value in params.items():
        kind = _PARAMS.get(key)
        if kind is None:
            _refuse(f"params.{_shown(key)}", "not a parameter of FOSModel")
        if value is None and key in _OPTIONAL:
            continue
        problem = _PARAM_CHECKS[kind](value)
        if problem:
            _refuse(f"params.{key}", f"{_shown(value)} {problem}")


def _integer(value: object, low: int, high: int) -> str | None:
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        return f"is not an integer from {low} to {high:,}"
    return None


def _number(value: object, low: float, high: float, *, open_low: bool = False) -> str | None:
    if (isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value)
            or not (low < value if open_low else low <= value) or value > high):
        return (f"is not a number over {low:g} up to {high:g}" if open_low else
                f"is not a number from {low:g} to {high:g}")
    return None


def _names(value: object) -> str | None:
    if (not isinstance(value, list) or len(value) > MAX_CANDIDATES
            or not all(isinstance(v, str) and 0 < len(v) <= MAX_NAME for v in value)):
        return "is not a list of column names"
    return None


def _lags(value: object) -> str | None:
    if not isinstance(value, Mapping) or len(value) > MAX_CANDIDATES:
        return "is not an object of channel names and lags"
    for name, lag in value.items():
        if len(name) > MAX_NAME or _integer(lag, 0, MAX_CANDIDATES):
            return f"gives channel {_shown(name)} the lag {_shown(lag)}, not an integer from 0 " \
                   f"to {MAX_CANDIDATES:,}"
    return None


def _taus(value: object) -> str | None:
    if not isinstance(value, list) or len(value) > MAX_CANDIDATES or any(
            _number(v, 0.0, MAX_ABS, open_low=True) for v in value):
        return "is not a list of time constants in seconds"
    return None


def _compensation(value: object) -> str | None:
    """Check that a compensation's names rebuild derived columns and its weights are bounded."""
    if not isinstance(value, Mapping) or len(value) > MAX_CANDIDATES:
        return "is not a map of derived column names to weights"
    try:
        weights = check_compensation(value)
    except InputError as exc:
        return f"is not a compensation ({exc})"
    if any(len(name) > MAX_NAME or abs(w) > MAX_ABS for name, w in weights.items()):
        return f"has a name over {MAX_NAME} characters or a weight over {MAX_ABS:g}"
    return None


_PARAM_CHECKS = {
    "compensation": _compensation,
    "bool": lambda v: None if isinstance(v, bool) else "is not true or false",
    "names": _names,
    "correlations": lambda v: None if v in ("fast", "reference") else "is not fast or reference",
    "degree": lambda v: _integer(v, 1, MAX_DEGREE),
    "fraction": lambda v: _number(v, 0.0, 1.0),
    "lags": _lags,
    "taus": _taus,
    "max_candidates": lambda v: _integer(v, 1, MAX_CANDIDATES),
    "lag": lambda v: _integer(v, 0, MAX_CANDIDATES),
    "count": lambda v: _integer(v, 1, MAX_CANDIDATES),
    "rate": lambda v: _number(v, 0.0, 1e9, open_low=True),
    "stop": lambda v: None if v in STOP_RULES else f"is not a stop rule ({', '.join(STOP_RULES)})",
    "tolerance": lambda v: _number(v, 0.0, 1.0),
}


def _candidate_count(params: Mapping[str, Any]) -> int:
    """Count the candidates of ``params`` from the sizes alone; refuse more than max_candidates.

    The count is :func:`~fosmodel.core.candidates.count_candidates`'s, which builds the list
    of lagged factors, a list as long as the lag a file asks for.
    """
    max_lag, degree = params.get("max_lag", 10), params.get("degree", 1)
    exog = params.get("exog_lags") or {}
    n_base = max_lag + sum(k + 1 for k in exog.values()) + len(params.get("levels") or [])
    product_lags = params.get("product_lags")
    n_products = n_base if product_lags is None else min(product_lags, max_lag)
    limit = min(params.get("max_candidates", 100_000), MAX_CANDIDATES)
    count = 1 + n_base + len(params.get("columns") or [])
    per_degree = n_products  # C(P + d - 1, d) for d = 1, 2, ...
    for d in range(2, degree + 1):
        if count > limit:
            break
        per_degree = per_degree * (n_products + d - 1) // d
        count += per_degree
    if count > limit:
        _refuse("params", f"max_lag {max_lag}, degree {degree} and the channels make more than "
                          f"{limit:,} candidates (params.max_candidates "
                          f"{params.get('max_candidates', 100_000):,}); no fit searches them")
    return count


# -- terms -----------------------------------------------------------------------------------


def _check_terms(fitted: Mapping[str, Any], params: Mapping[str, Any], count: int) -> None:
    names = fitted.get("terms")
    if not isinstance(names, list):
        _refuse("fitted.terms", "missing" if names is None else "not a list")
    recorded = fitted.get("n_candidates")
    if recorded != count:
        _refuse("fitted.n_candidates", f"{_shown(recorded)}, but the params make {count:,} "
                                       "candidates")
    if len(names) >= count:
        _refuse("fitted.terms", f"{len(names):,} terms, but the params make {count:,} "
                                "candidates, the constant among them")
    max_terms = params.get("max_terms")
    if max_terms is not None and len(names) > max_terms:
        _refuse("fitted.terms", f"{len(names):,} terms, more than params.max_terms {max_terms}")
    seen: dict[Term, int] = {}
    for i, name in enumerate(names):
        field = f"fitted.terms[{i}]"
        if not isinstance(name, str) or len(name) > MAX_NAME:
            _refuse(field, f"{_shown(name)} is not a term name")
        try:
            term = Term.parse(name, max_degree=params.get("degree", 1))
        except InputError as exc:
            _refuse(field, f"{exc} (params.degree {params.get('degree', 1)})"
                    if "product of more" in str(exc) else str(exc))
        if term.is_constant:
            _refuse(field, "the constant is the intercept, not a term")
        problem = _outside(term, params)
        if problem:
            _refuse(field, f"{name!r} {problem}")
        if term in seen:
            _refuse(field, f"{name!r} repeats fitted.terms[{seen[term]}]")
        seen[term] = i


def _outside(term: Term, params: Mapping[str, Any]) -> str | None:
    """Say how ``term`` falls outside the candidate set of ``params``; None if it is in it."""
    max_lag = params.get("max_lag", 10)
    exog = params.get("exog_lags") or {}
    levels = {level_name(t) for t in params.get("levels") or []}
    product_lags = params.get("product_lags")
    for ch, lag in term.factors:
        if lag is None:
            if ch not in (params.get("columns") or []):
                return f"reads column {ch!r}, which params.columns does not list"
            if term.degree > 1:
                return f"multiplies column {ch!r}, which enters only alone"
        elif is_level(ch):
            if ch not in levels:
                return f"reads {ch}, which params.levels does not offer"
        elif ch == OUTPUT:
            if not 1 <= lag <= max_lag:
                return f"lags the output by {lag} samples, outside 1 to params.max_lag {max_lag}"
        elif ch not in exog:
            return f"reads channel {ch!r}, which params.exog_lags does not list"
        elif lag > exog[ch]:
            return (f"lags {ch!r} by {lag} samples, beyond params.exog_lags.{ch} "
                    f"{exog[ch]}")
        if (term.degree > 1 and product_lags is not None
                and not (ch == OUTPUT and lag is not None and lag <= product_lags)):
            return (f"multiplies {ch}{'' if lag is None or is_level(ch) else f'[n-{lag}]'}, "
                    f"but params.product_lags {product_lags} keeps products to the output lags "
                    f"1 to {product_lags}")
    return None


# -- numbers ---------------------------------------------------------------------------------


def _check_numbers(fitted: Mapping[str, Any], params: Mapping[str, Any], version: int) -> None:
    n_terms = len(fitted["terms"])
    missing = {name for added, names in _ADDED_IN.items() if version < added for name in names}
    for key, check in _FITTED_NUMBERS.items():
        if key not in fitted:
            if key in missing:
                continue
            _refuse(f"fitted.{key}", "missing")
        check(f"fitted.{key}", fitted[key], n_terms)
    _check_offsets(fitted["offsets"], params)
    spread = math.sqrt(fitted["mse_null"])
    for i, (name, weight) in enumerate(zip(fitted["terms"], fitted["coef"])):
        term = Term.parse(name)
        if all(ch == OUTPUT or is_level(ch) for ch, _ in term.factors):
            gain = abs(weight) * spread ** (term.degree - 1)
            if not gain <= MAX_GAIN:
                _refuse(f"fitted.coef[{i}]", f"the weight {weight:g} of {name!r} is beyond any "
                        f"fit's: abs(w) s^(d-1) = {gain:.3g}, with s = {spread:.3g} the output's "
                        f"training spread (sqrt(fitted.mse_null)) and d = {term.degree} its "
                        f"degree; fits give at most {MAX_GAIN:g}")


def _value(field: str, value: object, *, nan: bool = False, positive: bool = False) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        _refuse(field, f"{_shown(value)} is not a number")
    if nan and math.isnan(value):
        return
    if not math.isfinite(value):
        _refuse(field, f"{value!r} is not a finite number")
    if abs(value) > MAX_ABS:
        _refuse(field, f"{value:g} is over {MAX_ABS:g} in magnitude")
    if positive and not value > 0:
        _refuse(field, f"{value:g} is not positive")


def _numbers(field: str, values: object, n_terms: int, *, nan: bool = False) -> None:
    if not isinstance(values, list):
        _refuse(field, f"{_shown(values)} is not a list")
    if len(values) != n_terms:
        _refuse(field, f"{len(values):,} values for {n_terms:,} terms")
    for i, v in enumerate(values):
        _value(f"{field}[{i}]", v, nan=nan)


def _integer_field(field: str, value: object, low: int) -> None:
    problem = _integer(value, low, 2**53)
    if problem:
        _refuse(field, f"{_shown(value)} {problem}")


def _text(field: str, value: object) -> None:
    if not isinstance(value, str) or len(value) > MAX_NAME:
        _refuse(field, f"{_shown(value)} is not a name")


_FITTED_NUMBERS = {
    "coef": _numbers,
    "intercept": lambda f, v, n: _value(f, v),
    "coef_se": lambda f, v, n: _numbers(f, v, n, nan=True),
    "intercept_se": lambda f, v, n: _value(f, v, nan=True),
    "mse_path": _numbers,
    "q": _numbers,
    "mse_null": lambda f, v, n: _value(f, v, positive=True),
    "n_samples": lambda f, v, n: _integer_field(f, v, n + 2),
    "n_dependent": lambda f, v, n: _integer_field(f, v, 0),
    "stop_reason": lambda f, v, n: _text(f, v),
    "target_name": lambda f, v, n: _text(f, v),
    "offsets": lambda f, v, n: None if isinstance(v, Mapping) else _refuse(f, "not an object"),
}


def _check_offsets(offsets: Mapping[str, Any], params: Mapping[str, Any]) -> None:
    """Refuse centring offsets other than one finite number per channel the model reads."""
    channels = {OUTPUT, *(params.get("exog_lags") or {}), *(params.get("columns") or [])}
    if set(offsets) != channels:
        extra = sorted(set(offsets) - channels)
        what = (f"has {_shown(extra[0])}, which the model does not read" if extra else
                f"lacks {sorted(channels - set(offsets))[0]!r}")
        _refuse("fitted.offsets", what)
    for name, value in offsets.items():
        _value(f"fitted.offsets.{name}", value)

