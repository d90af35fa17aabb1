"""Errors raise one of two classes, by the command line's exit code: UsageError (exit 2: an
option, a file or a model argument refused) and RuntimeFailure (exit 1: the run failed)."""
import microsim
import pytest
from microsim import models


def test_the_two_classes_are_exported_once():
    assert "UsageError" in microsim.__all__ and "RuntimeFailure" in microsim.__all__
    assert issubclass(microsim.UsageError, ValueError)
    assert issubclass(microsim.RuntimeFailure, RuntimeError)
    assert issubclass(microsim.ValidationFailed, microsim.RuntimeFailure)
    assert microsim.UsageError.__module__ == microsim.RuntimeFailure.__module__ == "microsim._core"


def test_a_refused_model_argument_is_a_usage_error():
    n = models.NDF("beckmann", 0.3, 0.7)
    with pytest.raises(microsim.UsageError, match="form must be"):
        models.G2(n, [0, 0, 1], [0, 0, 1], [0, 0, 1], "nonsense")
    with pytest.raises(microsim.UsageError, match="distribution must be"):
        models.NDF("nonsense", 0.3, 0.7)


def test_rays_beyond_memory_are_a_usage_error_naming_rays():
    """The CLI refuses them with exit 2 before the work (not std::bad_alloc, exit 1); Python names
    the keyword (the command line its option, --rays)."""
    s = microsim.generate("gaussian", alpha=0.5, resolution=16, seed=2)
    with pytest.raises(microsim.UsageError, match=r"^rays \d+ \(tallies of") as e:
        microsim.measure_g1(s, rays=10**12, theta=30)
    assert "--" not in str(e.value)


def test_the_library_names_parameters_as_keywords(cli, tmp_path):
    """A message of the library names its parameters: the keywords here, the options on the
    command line, otherwise word for word."""
    s = microsim.generate("gaussian", alpha=0.5, resolution=16, seed=2)
    with pytest.raises(microsim.UsageError) as e:
        microsim.measure_bsdf(s, material="mirror", eta=1.5, theta_i=30, phi_i=0, rays=1000)
    assert str(e.value) == "eta and k apply to material conductor or dielectric, not mirror"
    path = tmp_path / "s.exr"
    s.save(str(path))
    p = cli("measure", "bsdf", path, "--material", "mirror", "--eta", 1.5, "--theta-i", 30, "--phi-i", 0,
            "--rays", 1000, "-o", tmp_path / "x.json", check=False)
    assert p.returncode == 2
    assert p.stderr == "microsim: error: --eta and --k apply to --material conductor or dielectric, not mirror\n"
    # A value given keeps its braces: only the library's placeholders are spelled.
    with pytest.raises(microsim.UsageError) as e:
        microsim.generate("vcavity", ndf="{alpha}")
    assert str(e.value) == "ndf must be beckmann or ggx (got '{alpha}')"


def test_a_failed_run_is_a_runtime_failure():
    """Grooves of 10 degrees seen from 85 degrees on opposite sides: no facet faces both
    directions, exit 1 on the command line."""
    s = microsim.generate("vgroove", facet_angle=10.0)
    with pytest.raises(microsim.RuntimeFailure, match="no facet faces"):
        microsim.measure_g2(s, theta_o=85, phi_o=0, theta_i=85, phi_i=180, rays=100)
