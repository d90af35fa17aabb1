"""measure_bsdf and measure_albedo run the library's requests (no command line in between): the
records and the files equal the program's bit for bit (timings apart), and the requests' errors
are the program's, the parameters named as keywords."""
import json

import pytest

import microsim
from test_records import VOLATILE, differences

# The BSDF record's time of the analytic models beside the walks is a timing too.
TIMING = VOLATILE | {"model_seconds"}


@pytest.fixture(scope="module")
def tiles(tmp_path_factory, cli):
    folder = tmp_path_factory.mktemp("tiles")
    paths = [str(folder / "a.exr"), str(folder / "b.exr")]
    for seed, alpha, path in zip((9, 10), (0.5, 0.3), paths):
        cli("generate", "gaussian", "--alpha", alpha, "--resolution", 32, "--seed", seed, "-o", path)
    return [microsim.load(p) for p in paths]


def program_record(cli, tmp_path, *args, output="record.json"):
    out = tmp_path / output
    cli(*args, "-o", out)
    return json.loads(out.with_suffix(".json").read_text())


def program_args(options):
    """The command line's options for keyword arguments (flags for True)."""
    args = []
    for key, v in options.items():
        option = "--" + key.replace("_", "-")
        if v is True:
            args.append(option)
        elif isinstance(v, list):
            args += [option, ",".join(map(str, v))]
        else:
            args += [option, v]
    return args


BSDF_CASES = {
    "mirror": dict(material="mirror", theta_i=[60, 30], rays=3000, resolution=8),
    "conductor": dict(material="conductor", eta=0.2, k=3.0, theta_i=40, phi_i=[0, 90], rays=2000, resolution=8,
                      orders=3),
    "dielectric": dict(material="dielectric", eta=1.5, theta_i=20, rays=2000, resolution=8, no_models=True),
    "spectral": dict(material="conductor", metal="Au", wavelengths="450:650:100", theta_i=30, rays=2000,
                     resolution=8),
    "polarized": dict(material="conductor", eta=0.2, k=3.0, polarized=True, theta_i=30, rays=2000, resolution=8),
}


@pytest.mark.parametrize("case", list(BSDF_CASES))
def test_bsdf_equals_the_program(tiles, cli, tmp_path, case):
    options = BSDF_CASES[case]
    s = tiles[0]
    expected = program_record(cli, tmp_path, "measure", "bsdf", s.path, *program_args(options))
    record = microsim.measure_bsdf(s, seed=1, **options)
    assert differences(record, expected, skip=TIMING) == []
    if case == "spectral":
        assert record["parameters"]["wavelengths_nm"].tolist() == [450.0, 550.0, 650.0]
    if case == "polarized":
        assert "polarization" in record and record["parameters"]["polarized"] is True
    # Power: another seed differs in the measured values.
    other = microsim.measure_bsdf(s, seed=2, **options)
    assert any("/albedo" in d or "/rows" in d for d in differences(other, expected, skip=TIMING))


@pytest.mark.parametrize("output, options", [
    ("t.exr", dict(material="mirror", theta_i=[0, 40], rays=2000, resolution=8)),
    ("t.bsdf", dict(material="conductor", eta=0.2, k=3.0, theta_i="0:80:40", rays=1000, table_resolution=4,
                    table_azimuths=2, resolution=8, no_models=True)),
    ("t.pbsdf", dict(material="conductor", metal="Au", wavelengths="450:650:50", polarized=True,
                     theta_i="0:60:30", rays=1000, table_resolution=4, table_azimuths=2, resolution=8,
                     no_models=True)),
])
def test_bsdf_tables_equal_the_programs(tiles, cli, tmp_path, output, options):
    """The table and the record beside it, written from Python, are the program's."""
    s = tiles[0]
    ours, theirs = tmp_path / "ours", tmp_path / "theirs"
    ours.mkdir()
    theirs.mkdir()
    expected = program_record(cli, theirs, "measure", "bsdf", s.path, *program_args(options), output=output)
    record = microsim.measure_bsdf(s, output=str(ours / output), **options)
    assert differences(record, expected, skip=TIMING | {"summary_json"}) == []
    assert differences(json.loads((ours / output).with_suffix(".json").read_text()), expected, skip=TIMING) == []
    assert sorted(p.name for p in ours.iterdir()) == sorted(p.name for p in theirs.iterdir())
    if output != "t.exr":  # the EXR header names its own record's path
        assert (ours / output).read_bytes() == (theirs / output).read_bytes()


def test_albedo_ensemble_and_options_equal_the_program(tiles, cli, tmp_path):
    a, b = tiles
    options = dict(material="dielectric", eta=1.5, theta_i=[60, 30, 30], phi_i=45, azimuths=2, orders=3,
                   rays=2000, seed=3)
    expected = program_record(cli, tmp_path, "measure", "albedo", a.path, b.path, *program_args(options))
    record = microsim.measure_albedo([a, b], **options)
    assert record["file"] == [a.path, b.path]
    assert record["quadrature"]["nodes"] == 2
    assert differences(record, expected) == []
    other = microsim.measure_albedo([a, b], **dict(options, seed=4))
    assert any("/rows" in d for d in differences(other, expected))


def test_albedo_lookup_table_equals_the_programs(tiles, cli, tmp_path):
    a, b = tiles
    options = dict(material="conductor", metal="Au", wavelength_nm=600, mu_nodes=3, rays=2000)
    ours, theirs = tmp_path / "ours", tmp_path / "theirs"
    ours.mkdir()
    theirs.mkdir()
    expected = program_record(cli, theirs, "measure", "albedo", b.path, a.path, *program_args(options),
                              output="lut.exr")
    record = microsim.measure_albedo([b, a], output=str(ours / "lut.exr"), **options)
    assert differences(record, expected) == []
    assert sorted(p.name for p in ours.iterdir()) == ["lut.csv", "lut.exr", "lut.json"]
    assert sorted(p.name for p in theirs.iterdir()) == ["lut.csv", "lut.exr", "lut.json"]
    assert (ours / "lut.csv").read_text().splitlines()[0] == (theirs / "lut.csv").read_text().splitlines()[0]


# (function, keyword arguments, the program's arguments after the surface, the program's message)
ERRORS = [
    (microsim.measure_bsdf, dict(material="mirror", theta_i=[95, -5]), ["--material", "mirror", "--theta-i", "95,-5"],
     "--theta-i must be in [0, 90) degrees (got -5.00)"),
    (microsim.measure_bsdf, dict(material="mirror", theta_i=30, output="x.pbsdf"),
     ["--material", "mirror", "--theta-i", 30, "-o", "x.pbsdf"], "-o .pbsdf holds Mueller matrices: give --polarized"),
    (microsim.measure_bsdf, dict(material="mirror", theta_i=30, wavelengths=500),
     ["--material", "mirror", "--theta-i", 30, "--wavelengths", 500], "--wavelengths needs --metal or --ior-file"),
    (microsim.measure_bsdf, dict(material="mirror", theta_i=30, replicates=1),
     ["--material", "mirror", "--theta-i", 30, "--replicates", 1],
     "--replicates: must be an integer in [2, 65536] (got '1')"),
    (microsim.measure_bsdf, dict(material="bogus", theta_i=30), ["--material", "bogus", "--theta-i", 30],
     "--material must be mirror, conductor or dielectric (got 'bogus')"),
    (microsim.measure_bsdf, dict(material="mirror", theta_i=30, output="x.txt"),
     ["--material", "mirror", "--theta-i", 30, "-o", "x.txt"],
     "-o x.txt: unsupported output format (use .exr, .json, .bsdf, .binary, .pbsdf)"),
    (microsim.measure_albedo, dict(material="mirror", rays=10), ["--material", "mirror", "--rays", 10],
     "--rays must be at least --replicates per azimuth (32 here; got 10)"),
    (microsim.measure_albedo, dict(material="mirror", metal="Au"), ["--material", "mirror", "--metal", "Au"],
     "--metal applies to --material conductor only"),
    (microsim.measure_albedo, dict(material="mirror", mu_nodes=1), ["--material", "mirror", "--mu-nodes", 1],
     "--mu-nodes: must be an integer in [2, 64] (got '1')"),
    (microsim.measure_albedo, dict(material="mirror", theta_i=[30, 95]), ["--material", "mirror", "--theta-i", "30,95"],
     "--theta-i must be in [0, 90) degrees (got 95.00)"),
]


@pytest.mark.parametrize("measure, options, args, message", ERRORS)
def test_errors_are_the_programs_with_keywords(tiles, cli, tmp_path, measure, options, args, message):
    s = tiles[0]
    command = "bsdf" if measure is microsim.measure_bsdf else "albedo"
    if "-o" not in args:
        args = args + ["-o", tmp_path / "x.json"]
    p = cli("measure", command, s.path, *args, check=False)
    assert (p.returncode, p.stderr) == (2, f"microsim: error: {message}\n")
    keywords = message.replace("-o ", "output ").replace("--", "")
    for old, new in [("theta-i", "theta_i"), ("mu-nodes", "mu_nodes"), ("ior-file", "ior_file")]:
        keywords = keywords.replace(old, new)
    with pytest.raises(microsim.UsageError) as e:
        measure(s, **options)
    assert str(e.value) == keywords
    assert not list(tmp_path.iterdir())  # nothing half-written


def test_keywords_of_the_requests(tiles):
    s = tiles[0]
    with pytest.raises(microsim.UsageError, match=r"^measure_bsdf measures one surface \(got 2\)$"):
        microsim.measure_bsdf(tiles, material="mirror", theta_i=30)
    with pytest.raises(microsim.UsageError, match=r"^polarized: a flag takes True or False only$"):
        microsim.measure_bsdf(s, material="mirror", theta_i=30, polarized=1)
    with pytest.raises(microsim.UsageError, match=r"^unknown keyword 'theta' for measure_bsdf \(known: .*theta_i"):
        microsim.measure_bsdf(s, material="mirror", theta=30)
    with pytest.raises(microsim.UsageError, match=r"^theta_i is required$"):
        microsim.measure_bsdf(s, material="mirror")
    with pytest.raises(microsim.UsageError, match=r"^phi_i is one azimuth in degrees \(got '0,90'\)$"):
        microsim.measure_albedo(s, material="mirror", phi_i=[0, 90])
    # no_models=False is the default (the models beside); True leaves them out.
    on = microsim.measure_bsdf(s, material="mirror", theta_i=30, rays=1000, resolution=8, no_models=False)
    off = microsim.measure_bsdf(s, material="mirror", theta_i=30, rays=1000, resolution=8, no_models=True)
    assert on["parameters"]["models"] is True and off["parameters"]["models"] is False


def test_help_lists_the_keywords_from_the_library():
    text = microsim.help("measure bsdf")
    for keyword in ("material", "theta_i", "wavelengths", "polarized (False)", "no_models (False)",
                    "table_azimuths (16)", "rays (1000000)", "output", "threads"):
        assert "  " + keyword in text, keyword
    assert "  rays (200000)" in microsim.help("measure albedo")
    assert "  alpha (float, in (0, 10]): " in microsim.help("generate gaussian")
    assert "measure albedo" in microsim.help()
    with pytest.raises(microsim.UsageError, match="unknown command 'measure nothing'"):
        microsim.help("measure nothing")
