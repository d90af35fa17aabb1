"""measure_ndf, g1, g2 and vndf run the library's requests (no command line in between): the
records equal the program's bit for bit, and the requests' errors name the keywords."""
import json

import numpy as np
import pytest

import microsim
from test_records import VOLATILE, differences


@pytest.fixture(scope="module")
def tiles(tmp_path_factory, cli):
    folder = tmp_path_factory.mktemp("tiles")
    paths = [str(folder / "a.exr"), str(folder / "b.exr")]
    for seed, path in zip((9, 10), paths):
        cli("generate", "gaussian", "--alpha", 0.5, "--resolution", 32, "--seed", seed, "-o", path)
    return [microsim.load(p) for p in paths]


def program_record(cli, tmp_path, *args):
    out = tmp_path / "record.json"
    cli(*args, "-o", out)
    return json.loads(out.read_text())


def test_ndf_equals_the_program(tiles, cli, tmp_path):
    s = tiles[0]
    expected = program_record(cli, tmp_path, "measure", "ndf", s.path, "--theta-bins", 30, "--phi-bins", 12)
    record = microsim.measure_ndf(s, theta_bins=30, phi_bins=12)
    assert differences(record, expected) == []
    # Power: other bins give another record.
    assert differences(microsim.measure_ndf(s, theta_bins=31, phi_bins=12), expected)


def test_ndf_exr_output_writes_the_table(tiles, tmp_path):
    out = tmp_path / "d.exr"
    assert microsim.measure_ndf(tiles[0], output=str(out)) is None
    assert out.stat().st_size > 0


def test_g2_and_its_ensemble_equal_the_program(tiles, cli, tmp_path):
    a, b = tiles
    args = ["--theta-o", "30,60", "--theta-i", 40, "--phi-i", 180, "--rays", 8000, "--seed", 3]
    expected = program_record(cli, tmp_path, "measure", "g2", a.path, *args)
    record = microsim.measure_g2(a, theta_o=[30, 60], theta_i=40, phi_i=180, rays=8000, seed=3)
    assert differences(record, expected) == []
    expected = program_record(cli, tmp_path, "measure", "g2", a.path, b.path, *args)
    record = microsim.measure_g2([a, b], theta_o="30,60", theta_i=40, phi_i=180, rays=8000, seed=3)
    assert record["file"] == [a.path, b.path]
    assert differences(record, expected) == []
    assert differences(microsim.measure_g2(a, theta_o=[30, 60], theta_i=40, phi_i=180, rays=8000, seed=4),
                       expected)


def test_angle_lists_are_echoed_as_given(tiles, cli, tmp_path):
    """A range and floats reach the record as the command line's text would."""
    s = tiles[0]
    expected = program_record(cli, tmp_path, "measure", "vndf", s.path, "--theta", "0:60:30", "--phi", "0,22.5",
                              "--rays", 4000, "--sampler-samples", 0, "--theta-bins", 9, "--phi-bins", 8)
    record = microsim.measure_vndf(s, theta="0:60:30", phi=np.array([0, 22.5]), rays=4000, sampler_samples=0,
                                   theta_bins=9, phi_bins=8)
    assert record["parameters"]["phi"] == "0.0,22.5" and expected["parameters"]["phi"] == "0,22.5"
    assert differences(record, expected, skip=VOLATILE | {"parameters"}) == []


def test_threads_reach_the_record(tiles):
    assert microsim.measure_g1(tiles[0], theta=30, rays=2000, threads=1)["threads"] == 1


@pytest.mark.parametrize("measure, options, message", [
    (microsim.measure_g2, {"theta_o": 30}, "theta_i is required"),
    (microsim.measure_g2, {"theta_o": 95, "theta_i": 30}, "theta_o must be in [0, 90) degrees (got 95.00)"),
    (microsim.measure_g1, {"theta": 90}, "theta must be in [0, 90) degrees, or (90, 180] for the undersurface "
                                         "of a mesh (got 90.00)"),
    (microsim.measure_g1, {"theta": "1,,2"}, "theta '1,,2': empty item (a leading, trailing or doubled ',')"),
    (microsim.measure_g1, {"phi": 4000}, "phi must be azimuths in [-3600, 3600] degrees (got 4000)"),
    (microsim.measure_g1, {"replicates": 1}, "replicates: must be an integer in [2, 65536] (got '1')"),
    (microsim.measure_g1, {"rays": 1.5}, "rays: unsupported value 1.5"),
    (microsim.measure_g1, {"output": "g1.txt"}, "output g1.txt: unsupported output format (use .json, .csv)"),
    (microsim.measure_g1, {"threads": -1}, "threads: must be an integer in [0, 4096] (got '-1')"),
    (microsim.measure_vndf, {"phi_bins": 0}, "phi_bins: must be an integer in [1, 720] (got '0')"),
    (microsim.measure_vndf, {"sampler_samples": -1}, "sampler_samples: must be an integer in [0, 1000000000000] "
                                                     "(got '-1')"),
    (microsim.measure_ndf, {"theta_bins": 0}, "theta_bins: must be an integer in [1, 3600] (got '0')"),
])
def test_request_errors_name_the_keywords(tiles, measure, options, message):
    with pytest.raises(microsim.UsageError) as e:
        measure(tiles[0], **options)
    assert str(e.value) == message


def test_ndf_measures_one_surface(tiles):
    with pytest.raises(microsim.UsageError, match=r"measure_ndf measures one surface \(got 2\)"):
        microsim.measure_ndf(tiles)


def test_generate_reads_a_preset_and_the_keywords_win(cli, tmp_path):
    """generate runs the library's surface request: a preset (config) as the command line reads
    it, the keywords over it, the same heights as the program's file."""
    preset = tmp_path / "p.toml"
    preset.write_text("alpha = 0.3\nresolution = 16\nseed = 5\n")
    path = tmp_path / "s.exr"
    cli("generate", "gaussian", "--config", preset, "--seed", 6, "-o", path)
    s = microsim.generate("gaussian", config=str(preset), seed=6)
    assert s.description["alpha_x"] == 0.3 and s.heights.shape == (16, 16)
    assert np.array_equal(s.heights, microsim.load(str(path)).heights)
    assert not np.array_equal(s.heights, microsim.generate("gaussian", config=str(preset)).heights)


def test_generate_names_a_missing_required_keyword():
    with pytest.raises(microsim.UsageError) as e:
        microsim.generate("heightmap")
    assert str(e.value) == "input is required"


def test_validate_equals_the_program(tiles, cli, tmp_path):
    a, b = tiles
    out = tmp_path / "v.json"
    p = cli("validate", a.path, b.path, "--checks", "d_identities,g1", "--theta", 30, "--rays", 4000, "-o", out,
            check=False)
    expected = json.loads(out.read_text())
    record = microsim.validate([a, b], checks=["d_identities", "g1"], theta=30, rays=4000)
    assert p.returncode == 0 and record["files"] == [a.path, b.path]
    assert differences(record, expected, skip=VOLATILE | {"seconds"}) == []
    assert record["parameters"]["overrides"]["checks"] == "d_identities,g1"
    assert differences(microsim.validate([a, b], checks="d_identities,g1", theta=30, rays=4000, seed=2), expected)


def test_validate_needs_surfaces_or_a_suite():
    with pytest.raises(microsim.UsageError, match=r"^validate: give either surface FILE\(s\) or suite NAME \(known suites: .*smoke"):
        microsim.validate()
