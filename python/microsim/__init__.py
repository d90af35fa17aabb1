"""microsim: explicit microsurface Monte Carlo simulator.

Surfaces are generated or loaded as :class:`Surface` objects (heights as a numpy view), measured
with the same code, options and records as the command line (``microsim measure g1 ...``), and
compared with the analytic models of :mod:`microsim.models`.

Keyword arguments are the command line's long options with ``_`` for ``-``
(``correlation_length=0.02`` is ``--correlation-length 0.02``); lists of angles are given as
lists, numbers or the command line's text (``theta=[30, 80]`` is ``--theta 30,80``), ``True`` a
flag. ``help("measure g1")`` lists them. Every function sets the fields of the library's request
(``_core.G1Request``, ``_core.BsdfRequest`` ...) directly and runs it; no command line is parsed.
Records are the command's JSON as dicts and lists, numeric arrays as numpy arrays, bit for bit
what ``-o record.json`` writes at the same seed. Errors raise the library's message, its parameters named as the keywords
(``rays: must be ...``), as :class:`UsageError` (a ``ValueError``) where the command line exits 2
(an option, a file or a model argument refused) and as :class:`RuntimeFailure` (a
``RuntimeError``) where it exits 1 (the run failed); both are defined once, in the compiled core, and raised by
:mod:`microsim.models` too. Measurements release the GIL.
"""
from . import _core
from ._core import RuntimeFailure, Surface, UsageError, load, models, surface_kinds

__all__ = ["Surface", "UsageError", "RuntimeFailure", "ValidationFailed", "generate", "load",
           "measure_ndf", "measure_g1", "measure_g2", "measure_vndf", "measure_bsdf", "measure_albedo",
           "validate",
           "help", "models", "surface_kinds"]


class ValidationFailed(RuntimeFailure):
    """An exact identity FAILED in ``validate``; ``record`` holds the evidence."""

    def __init__(self, message, record):
        super().__init__(message)
        self.record = record


def _surfaces(surfaces):
    """The records' names of the surfaces (their files when loaded) and the name map."""
    if isinstance(surfaces, Surface):
        surfaces = [surfaces]
    surfaces = list(surfaces)
    if not surfaces:
        raise UsageError("no surface given")
    names, by_name = [], {}
    for k, s in enumerate(surfaces):
        if not isinstance(s, Surface):
            raise UsageError(f"surface {k}: expected a microsim.Surface (from generate or load), got {type(s).__name__}")
        name = s.path if s.path is not None else f"<surface {k}: {s.description.get('kind', 'surface')}>"
        if by_name.get(name, s) is not s:
            name = f"<surface {k}>"
        by_name[name] = s
        names.append(name)
    return names, by_name


def _refuse_shard(options):
    # A shard's tallies are a part of a run, meaningful only merged with the others: a record
    # finalised from them would look whole and be wrong.
    if options.get("shard") is not None:
        raise UsageError("shard: a partial run is written by the command line (--shard K/N) and "
                         "read back by its merge; Python measures whole runs")


def generate(kind, **options):
    """A new surface: ``generate("gaussian", alpha=0.5, resolution=128, seed=9)``.

    ``kind`` and the options are those of ``microsim generate KIND`` (``help("generate gaussian")``,
    ``surface_kinds()[kind]["options"]``: the library's table, keywords with ``_`` for ``-``);
    ``output="file.exr"`` also saves it."""
    # Nothing is written unless output is given; the default name only passes the extension
    # checks (a heightmap is saved as .exr, every other kind accepts a mesh file).
    _refuse_shard(options)
    output = options.pop("output", None)
    threads = options.pop("threads", None) or 0
    config = options.pop("config", None)
    options.pop("quiet", None)  # nothing is printed here but the warnings
    given = []
    for key, v in options.items():
        if v is None or v is False:
            continue
        given.append((key.replace("_", "-"), "true" if v is True else _item_text(key, v)))
    default = "surface.exr" if kind == "heightmap" else "surface.ply"
    return _core._generate(kind, given, config, output or default, output is not None, threads)


# The requests' fields that are lists of angles: given as a list, a number or the command line's
# text; the record's parameters echo the text.
_ANGLE_LISTS = {"theta", "phi", "theta_o", "phi_o", "theta_i", "phi_i", "wavelengths"}
# The fields that are the command line's flags: True or False.
_FLAGS = {"polarized", "no_models"}


def _item_text(name, v):
    if hasattr(v, "item") and getattr(v, "ndim", 1) == 0:  # numpy scalar
        v = v.item()
    if isinstance(v, bool) or not isinstance(v, (int, float, str)):
        raise UsageError(f"{name}: unsupported value {v!r}")
    return repr(v) if isinstance(v, float) else str(v)  # shortest text that reads back as the same double


def _angle_text(name, v):
    if isinstance(v, (list, tuple)) or (hasattr(v, "tolist") and getattr(v, "ndim", 0) > 0):
        items = v.tolist() if hasattr(v, "tolist") else v
        return ",".join(_item_text(name, x) for x in items)
    return _item_text(name, v)


def _fields(request):
    return [k for k in dir(request) if not k.startswith("_") and k not in ("surface", "surfaces")]


def _set_field(request, command, key, v):
    if key not in _fields(request):
        raise UsageError(f"unknown keyword '{key}' for {command} (known: {', '.join(_fields(request))}, "
                         "output, threads)")
    if key in _FLAGS:
        if not isinstance(v, bool):
            raise UsageError(f"{key}: a flag takes True or False only")
        setattr(request, key, v)
        return
    if key in _ANGLE_LISTS:
        v = _angle_text(key, v)
    elif key == "checks" and isinstance(v, (list, tuple)):
        v = ",".join(map(str, v))
    elif hasattr(v, "item") and getattr(v, "ndim", 1) == 0:  # numpy scalar
        v = v.item()
    if isinstance(v, bool):
        raise UsageError(f"{key}: unsupported value {v!r}")
    try:
        setattr(request, key, v)
    except TypeError:
        raise UsageError(f"{key}: unsupported value {v!r}") from None


def _run_request(quantity, request, run, surfaces, options, one_surface=False):
    """Sets the request's fields from the keyword arguments and runs it (the library's record)."""
    _refuse_shard(options)
    output = options.pop("output", None)
    threads = options.pop("threads", None) or 0
    options.pop("quiet", None)  # nothing is printed here
    names, by_name = _surfaces(surfaces)
    if one_surface:
        if len(names) != 1:
            raise UsageError(f"measure_{quantity} measures one surface (got {len(names)})")
        request.surface = (names[0], by_name[names[0]])
    else:
        request.surfaces = [(n, by_name[n]) for n in names]
    for key, v in options.items():
        if v is not None:
            _set_field(request, f"measure_{quantity}", key, v)
    return run(request, output, threads)


def measure_ndf(surface, **options):
    """D over the sphere from the facets (``microsim measure ndf``); one surface. ``output="d.exr"``
    writes the EXR table instead of a record (and returns None)."""
    return _run_request("ndf", _core.NdfRequest(), _core._measure_ndf, surface, options, one_surface=True)


def measure_g1(surfaces, **options):
    """Masking G1 (``microsim measure g1``): ``measure_g1(s, theta=[30, 80], phi=0, rays=100000, seed=4)``.

    A list of surfaces is an ensemble (rows with the between-surface standard error)."""
    return _run_request("g1", _core.G1Request(), _core._measure_g1, surfaces, options)


def measure_g2(surfaces, **options):
    """Masking-shadowing G2 (``microsim measure g2``)."""
    return _run_request("g2", _core.G2Request(), _core._measure_g2, surfaces, options)


def measure_vndf(surfaces, **options):
    """Distribution of visible normals (``microsim measure vndf``)."""
    return _run_request("vndf", _core.VndfRequest(), _core._measure_vndf, surfaces, options)


def measure_bsdf(surface, **options):
    """BSDF per scattering order (``microsim measure bsdf``); one surface. ``output="t.exr"`` (or
    .bsdf, .binary, .pbsdf) also writes the table, and the record beside it (``t.json``)."""
    return _run_request("bsdf", _core.BsdfRequest(), _core._measure_bsdf, surface, options, one_surface=True)


def measure_albedo(surfaces, **options):
    """Directional albedo E(mu) per scattering order at Gauss-Legendre nodes in mu and its average
    E_avg with statistical and quadrature errors (``microsim measure albedo``):
    ``measure_albedo([s1, s2], material="mirror", mu_nodes=8, rays=100000)``. Each surface is
    measured on its own; ``output="lut.exr"`` also writes the lookup table E(mu, alpha)."""
    return _run_request("albedo", _core.AlbedoRequest(), _core._measure_albedo, surfaces, options)


def validate(surfaces=None, **options):
    """Every applicable check (``microsim validate``) of a surface, an ensemble, or
    ``suite="smoke"``; raises :class:`ValidationFailed` (with ``.record``) when an exact identity fails."""
    _refuse_shard(options)
    output = options.pop("output", None)
    threads = options.pop("threads", None) or 0
    options.pop("quiet", None)  # nothing is printed here but the warnings
    request = _core.ValidateRequest()
    if surfaces is not None:
        names, by_name = _surfaces(surfaces)
        request.surfaces = [(n, by_name[n]) for n in names]
    for key, v in options.items():
        if v is not None:
            _set_field(request, "validate", key, v)
    record, failure = _core._validate(request, output, threads)
    if failure is not None:
        raise ValidationFailed(failure, record)
    return record


# The functions of the commands and the library requests whose fields are their keywords.
_REQUESTS = {
    "measure ndf": ("NdfRequest", "measure_ndf"),
    "measure g1": ("G1Request", "measure_g1"),
    "measure g2": ("G2Request", "measure_g2"),
    "measure vndf": ("VndfRequest", "measure_vndf"),
    "measure bsdf": ("BsdfRequest", "measure_bsdf"),
    "measure albedo": ("AlbedoRequest", "measure_albedo"),
    "validate": ("ValidateRequest", "validate"),
}


def _kind_help(name, kind):
    lines = [f"generate({name!r}, ...): {kind['help']}", "keywords:"]
    for o in kind["options"]:
        facts = [o["type"]]
        if o["default"] is not None:
            facts.append(f"default {o['default']}")
        if o["range"] is not None:
            facts.append(f"in {o['range']}")
        if o["required"]:
            facts.append("required")
        lines.append(f"  {o['keyword']} ({', '.join(facts)}): {o['help']}")
    return "\n".join(lines)


def help(command=""):
    """The keywords of a function, built from the library's tables: ``help("measure g1")`` lists the
    fields of its request with their defaults, ``help("generate gaussian")`` the surface kind's
    options with their types, ranges and descriptions; ``help()`` lists the commands. (The
    command line's ``microsim COMMAND --help`` describes every option in words.)"""
    words = command.split()
    kinds = surface_kinds()
    if not words:
        return ("commands: " + ", ".join(["generate KIND"] + list(_REQUESTS)) + "\nsurface kinds: " +
                ", ".join(kinds))
    if words[0] == "generate":
        if len(words) == 1:
            return "generate(kind, **options), kind one of: " + ", ".join(kinds)
        if words[1] not in kinds:
            raise UsageError(f"unknown surface kind '{words[1]}' (known: {', '.join(kinds)})")
        return _kind_help(words[1], kinds[words[1]])
    key = " ".join(words)
    if key not in _REQUESTS:
        raise UsageError(f"unknown command '{key}' (known: generate, {', '.join(_REQUESTS)})")
    request_class, function = _REQUESTS[key]
    request = getattr(_core, request_class)()
    lines = [f"{function}: {' '.join(globals()[function].__doc__.split())}", "keywords (default):"]
    lines += [f"  {k} ({getattr(request, k)!r})" for k in _fields(request)]
    lines += ["  output (None: the record only)", "  threads (0: all cores)"]
    return "\n".join(lines)
