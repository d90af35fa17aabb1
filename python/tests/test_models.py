"""microsim.models against independent routes: closed forms written here, the C++ values in
the records, and integrals of the distributions themselves."""
import math

import numpy as np
import pytest

import microsim
from microsim import models as M

NDFS = [M.NDF("beckmann", 0.5), M.NDF("ggx", 0.5), M.NDF("beckmann", 0.3, 0.7), M.NDF("ggx", 0.8, 0.25)]


def sphere_grid(n_theta=1200, n_phi=720, hemisphere=True):
    """Midpoint rule over the (upper) sphere: directions and solid-angle weights."""
    top = math.pi / 2 if hemisphere else math.pi
    t = (np.arange(n_theta) + 0.5) * top / n_theta
    p = (np.arange(n_phi) + 0.5) * 2 * math.pi / n_phi
    T, P = np.meshgrid(t, p, indexing="ij")
    w = np.sin(T) * (top / n_theta) * (2 * math.pi / n_phi)
    return M.direction(T, P), w


def test_lambda_against_closed_forms():
    a = np.array([0.05, 0.3, 1.0, 2.5])
    # (erf(a) - 1)/2 written with erfc: no cancellation at large a.
    beckmann = [-math.erfc(x) / 2 + math.exp(-x * x) / (2 * x * math.sqrt(math.pi)) for x in a]
    ggx = [(-1 + math.sqrt(1 + 1 / (x * x))) / 2 for x in a]
    assert np.allclose(M.beckmann_lambda(a), beckmann, rtol=1e-10, atol=0)
    assert np.allclose(M.ggx_lambda(a), ggx, rtol=1e-12, atol=0)
    # Lambda(v) of an anisotropic NDF through alpha_o [Heitz14, eq. 11]: a = 1 / (alpha_o tan theta).
    ndf = M.NDF("beckmann", 0.3, 0.7)
    theta, phi = 1.1, 0.6
    a_v = 1 / (math.sqrt((0.3 * math.cos(phi)) ** 2 + (0.7 * math.sin(phi)) ** 2) * math.tan(theta))
    assert ndf.Lambda(M.direction(theta, phi)) == pytest.approx(float(M.beckmann_lambda(a_v)), rel=1e-12)
    assert ndf.G1(M.direction(theta, phi)) == pytest.approx(1 / (1 + float(M.beckmann_lambda(a_v))), rel=1e-12)
    assert math.isinf(ndf.Lambda([1.0, 0.0, 0.0]))


@pytest.mark.parametrize("ndf", NDFS, ids=repr)
def test_distributions_are_normalized(ndf):
    m, w = sphere_grid()
    # [GeomBSDF24, eq. 1c]: integral of D(m) (n.m) over the hemisphere is 1.
    assert float((ndf.D(m) * m[..., 2] * w).sum()) == pytest.approx(1.0, abs=2e-4)
    # [Heitz14, eq. 13]: the visible normals of a view are a distribution (this ties Lambda to D).
    v = M.direction(1.4, 0.7)
    dv = ndf.D_visible(v, m)
    assert float((dv * w).sum()) == pytest.approx(1.0, abs=2e-4)
    # Power: half the Lambda breaks the normalization.
    wrong = dv * (1 + ndf.Lambda(v)) / (1 + 0.5 * ndf.Lambda(v))
    assert abs(float((wrong * w).sum()) - 1.0) > 1e-2


@pytest.mark.parametrize("ndf", NDFS, ids=repr)
def test_visible_normal_sampling(ndf):
    # Mean of m.z and m.x of the exact sampler against the integrals of D_visible, with the
    # sample's own standard error (z < 4.5 over 4 NDFs x 2 moments).
    v = M.direction(1.0, 0.3)
    rng = np.random.default_rng(7)
    n = 200000
    s = ndf.sample_visible_normal(v, rng.random(n), rng.random(n))
    m, w = sphere_grid()
    dv = ndf.D_visible(v, m) * w
    for c in (0, 2):
        exact = float((dv * m[..., c]).sum())
        se = s[:, c].std() / math.sqrt(n)
        assert abs(s[:, c].mean() - exact) < 4.5 * se
    # Power: the sampler of another roughness is far off.
    other = M.NDF(ndf.distribution, 1.5 * ndf.alpha_x, 1.5 * ndf.alpha_y).sample_visible_normal(v, rng.random(n), rng.random(n))
    exact = float((dv * m[..., 2]).sum())
    assert abs(other[:, 2].mean() - exact) > 10 * other[:, 2].std() / math.sqrt(n)


def test_g2_forms():
    ndf = M.NDF("ggx", 0.6)
    o, i, m = M.direction(1.0, 0.0), M.direction(0.8, 2.0), np.array([0.0, 0.0, 1.0])
    lo, li = ndf.Lambda(o), ndf.Lambda(i)
    phi = 2.0
    forms = M.g2_forms_from_lambda(lo, li, phi)
    assert M.G2(ndf, o, i, m, "height_correlated") == pytest.approx(1 / (1 + lo + li), rel=1e-14)  # [Heitz14, eq. 21]
    assert M.G2(ndf, o, i, m, "separable") == pytest.approx(ndf.G1(o) * ndf.G1(i), rel=1e-14)  # eq. 20
    for name in ("separable", "height_correlated", "direction_correlated", "height_direction_correlated"):
        assert M.G2(ndf, o, i, m, name) == pytest.approx(forms[name], rel=1e-12)
    # [GeomBSDF24, eq. 16]: G2(v, m, v) = G1(v, m) for the V-cavity, and a back-facing normal gives 0.
    assert M.G2(ndf, o, o, m, "vcavity") == M.vcavity_G1(o, m)
    assert M.G2(ndf, o, i, -m, "height_correlated") == 0.0
    # Broadcasting: many o against one i.
    many = M.direction(np.linspace(0.1, 1.4, 5), 0.0)
    assert M.G2(ndf, many, i, m).shape == (5,)
    with pytest.raises(ValueError, match="form must be"):
        M.G2(ndf, o, i, m, "nonsense")


def test_fresnel():
    eta = 1.5
    c = np.linspace(0.01, 1.0, 50)
    # Energy: R + T = 1 for a dielectric [GeomBSDF24, eq. 8].
    assert np.allclose(M.fresnel_dielectric(c, eta) + M.fresnel_dielectric_transmittance(c, eta), 1.0, atol=1e-12)
    assert M.fresnel_dielectric(1.0, eta) == pytest.approx(((eta - 1) / (eta + 1)) ** 2, rel=1e-12)
    # A conductor without absorption is the dielectric of the same index.
    assert np.allclose(M.fresnel_conductor(c, eta, 0.0), M.fresnel_dielectric(c, eta), rtol=1e-12)
    rs, rp = M.fresnel_dielectric_sp(0.5, eta)
    assert (rs + rp) / 2 == pytest.approx(float(M.fresnel_dielectric(0.5, eta)), rel=1e-14)
    # Total internal reflection from the dense side beyond the critical angle.
    assert M.fresnel_dielectric(0.2, 1 / eta) == 1.0


def test_microfacet_bsdf():
    ndf = M.NDF("beckmann", 0.4)
    o, i = M.direction(0.9, 0.2), M.direction(0.4, 2.5)
    for material in (M.Material.mirror(), M.Material.conductor(0.2, 3.0), M.Material.dielectric(1.5)):
        f = M.MicrofacetBSDF(ndf, material)
        assert f.eval(o, i) == pytest.approx(f.eval(i, o), rel=1e-14)  # reciprocity
    # [Heitz14, eq. 18] by hand: F G2 D / (4 |o.n| |i.n|) at the half vector, mirror.
    f = M.MicrofacetBSDF(ndf)
    h = (o + i) / np.linalg.norm(o + i)
    expect = M.G2(ndf, o, i, h) * ndf.D(h) / (4 * o[2] * i[2])
    assert f.eval(o, i) == pytest.approx(expect, rel=1e-12)
    # Weak white furnace [Heitz14, eq. 19]: with masking only, int f(o, i) |i.n| d omega_i = 1 over
    # the whole sphere, for every o; with the height-correlated G2 less (shadowing).
    i_all, w = sphere_grid(1200, 600, hemisphere=False)
    o = M.direction(1.0, 0.0)
    furnace = M.MicrofacetBSDF(ndf, masking="smith_masking_only").eval(o, i_all) * np.abs(i_all[..., 2])
    assert float((furnace * w).sum()) == pytest.approx(1.0, abs=1e-3)
    shadowed = M.MicrofacetBSDF(ndf).eval(o, i_all) * np.abs(i_all[..., 2])
    assert float((shadowed * w).sum()) < 0.99
    # A dielectric splits the energy; with height-correlated masking some is lost to single scattering.
    r, t = M.MicrofacetBSDF(ndf, M.Material.dielectric(1.5)).albedo(M.direction(1.0, 0.0))
    assert 0 < r < 0.2 and 0.6 < t < 1 and r + t < 1


def test_models_equal_the_records_nominal_columns():
    # The measured record's smith_nominal column is the library's model: the same numbers.
    s = microsim.generate("gaussian", alpha=0.4, resolution=16, seed=2)
    record = microsim.measure_g1(s, theta=[20, 50, 75], phi=30, rays=512, replicates=2)
    ndf = M.NDF("beckmann", 0.4)
    for row in record["rows"]:
        v = M.direction(math.radians(row["theta_deg"]), math.radians(row["phi_deg"]))
        assert ndf.G1(v) == pytest.approx(row["smith_nominal"], rel=1e-14)
    with pytest.raises(ValueError):
        M.NDF("lambertian", 0.5)


def test_spectral_conductor_tables_and_colour():
    # Johnson and Christy's gold at a tabulated wavelength, and halfway to the next row.
    assert M.metal_index("Au", 548.6) == (0.43, 2.455)
    n, k = M.metal_index("Au", (548.6 + 582.1) / 2)
    assert n == pytest.approx((0.43 + 0.29) / 2, rel=1e-12) and k == pytest.approx((2.455 + 2.863) / 2, rel=1e-12)
    assert set(M.metal_names()) >= {"Au", "Ag", "Cu", "Al"}
    # A constant spectrum is the white point; gold's reflectance is red.
    nm = [450, 500, 550, 600, 650]
    assert np.allclose(M.spectrum_to_rgb(nm, [0.7] * 5), 0.7, rtol=1e-12)
    R = [((n - 1) ** 2 + k ** 2) / ((n + 1) ** 2 + k ** 2) for n, k in (M.metal_index("Au", x) for x in nm)]
    r, g, b = M.spectrum_to_rgb(nm, R)
    assert r > g > b


def test_compensation_maps_in_the_exr_orientation():
    """Energy-compensation maps (image order of the measure bsdf EXR): the Kulla-Conty map integrates to
    1 - E_ss, and the single-scattering lobe for light from +x peaks on the -x side (left columns), where the
    Smith walk's exits (all orders) peak too."""
    R = 16
    c = M.hemisphere_cos_integrals(R)
    assert abs(c.sum() - math.pi) < 1e-12
    t = M.EssTable(M.NDF("beckmann", 0.5))
    i = [math.sin(math.radians(60)), 0.0, math.cos(math.radians(60))]
    kc = M.compensation_map(t, M.Material.mirror(), "kulla_conty", i, R)
    assert abs((kc * c).sum() - (1 - float(t.E(0.5)))) < 2e-5
    single = M.compensation_map(t, M.Material.mirror(), "single", i, R)
    walk1, _ = M.smith_walk_map(M.NDF("beckmann", 0.5), M.Material.mirror(), i, R, 1, 100000)
    col = np.unravel_index(np.argmax(single), single.shape)[1]
    assert col < R // 2
    assert np.unravel_index(np.argmax(walk1), walk1.shape)[1] == col
    assert M.hellinger_distance(single, walk1) < 0.1
    assert M.hellinger_distance(single, single[:, ::-1]) > 0.5


def test_vcavity_multiple_map_in_the_exr_orientation():
    """The V-cavity multiple-scattering map (image order of the measure bsdf EXR): with a mirror all orders
    hold an albedo of 1, the map of orders >= 2 holds the albedo returned with it, and the lobe of all orders
    for light from +x peaks in the left column like the single-scattering lobe (its mirror image does not)."""
    R = 16
    c = M.hemisphere_cos_integrals(R)
    ndf = M.NDF("beckmann", 0.5)
    i = [math.sin(math.radians(60)), 0.0, math.cos(math.radians(60))]
    all_orders, a1, total = M.vcavity_multiple_map(ndf, M.Material.mirror(), i, R, 1, 4, 256, 256)
    ms, a2, _ = M.vcavity_multiple_map(ndf, M.Material.mirror(), i, R, 2, 4, 256, 256)
    assert abs(total - 1) < 1e-12 and abs(a1 - 1) < 1e-12
    assert abs((all_orders * c).sum() - 1) < 1e-12
    assert abs((ms * c).sum() - a2) < 1e-12 and 0.05 < a2 < 0.2
    single = M.compensation_map(M.EssTable(ndf), M.Material.mirror(), "single", i, R)
    assert np.unravel_index(np.argmax(all_orders), all_orders.shape)[1] == 0
    assert np.unravel_index(np.argmax(single), single.shape)[1] == 0
    assert M.hellinger_distance(single, all_orders) < 0.1
    assert M.hellinger_distance(single, all_orders[:, ::-1]) > 0.5
