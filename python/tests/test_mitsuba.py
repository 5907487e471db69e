"""The Mitsuba 3 plugin: conventions, variants, and unbiasedness in a rendered scene."""

import numpy as np
import pytest

import mitsuba as mi  # noqa: E402  (a missing mitsuba must fail, not skip)
import drjit as dr  # noqa: E402

import diffbsdf  # noqa: E402

CU = {"type": "roughconductor", "distribution": "ggx", "alpha": 0.3, "material": "Cu"}
GLASS = {"type": "roughdielectric", "distribution": "beckmann", "alpha": 0.3, "int_ior": 1.5, "ext_ior": 1.0}


@pytest.fixture(scope="module")
def llvm():
    mi.set_variant("llvm_ad_rgb")
    import diffbsdf.mitsuba_bsdf as dm

    dm.register()
    dm.wavefront()
    return dm


def learned(models, nested, name="conductor-ggx-a0.3-cu-disk.dbsdf", **extra):
    return {"type": "diffbsdf", "model": str(models / name), "bsdf": nested, **extra}


def interaction(wi: np.ndarray):
    si = dr.zeros(mi.SurfaceInteraction3f, wi.shape[0])
    si.wi = mi.Vector3f(np.ascontiguousarray(wi.T))
    si.wavelengths = dr.zeros(mi.Color0f) if hasattr(mi, "Color0f") else si.wavelengths
    return si


def directions(n, seed, lower_fraction=0.0):
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    v[:, 2] = np.abs(v[:, 2]) + 0.05
    v[: int(n * lower_fraction), 2] *= -1
    return (v / np.linalg.norm(v, axis=1, keepdims=True)).astype(np.float32)


def test_sample_conventions_disk(llvm, models):
    bsdf = mi.load_dict(learned(models, CU))
    nested = mi.load_dict(CU)
    model = diffbsdf.Model.load(models / "conductor-ggx-a0.3-cu-disk.dbsdf")
    n = 4096
    wi = directions(n, 1, lower_fraction=0.25)
    u = np.random.default_rng(2).random((n, 2), dtype=np.float32)
    si = interaction(wi)
    ctx = mi.BSDFContext()
    bs, weight = bsdf.sample(ctx, si, mi.Float(np.zeros(n, np.float32)), mi.Point2f(np.ascontiguousarray(u.T)))
    wo = np.asarray(bs.wo.numpy()).T
    pdf = np.asarray(bs.pdf.numpy())
    above = wi[:, 2] > 0
    # above the surface: exactly the model's sample (si.wi is our wi, bs.wo our wo)
    ref_wo, ref_pdf, ref_valid = model.sample(wi[above], u[above])
    np.testing.assert_allclose(wo[above][ref_valid], ref_wo[ref_valid], atol=1e-6)
    np.testing.assert_allclose(pdf[above], ref_pdf, rtol=1e-6)
    # below: mirrored through the surface (z -> -z), as `twosided` does
    ref_wo_b, ref_pdf_b, ref_valid_b = model.sample(wi[~above] * np.float32([1, 1, -1]), u[~above])
    np.testing.assert_allclose(wo[~above][ref_valid_b], ref_wo_b[ref_valid_b] * np.float32([1, 1, -1]), atol=1e-6)
    # pdf() agrees with the sampled pdf; weight = nested eval (cosine included) / pdf
    again = np.asarray(bsdf.pdf(ctx, si, bs.wo).numpy())
    ok = pdf > 0
    assert np.max(np.abs(again[ok] - pdf[ok]) / pdf[ok]) <= 1e-4
    value = np.asarray(nested.eval(ctx, si, bs.wo).numpy()).T
    w = np.asarray(weight.numpy()).T
    np.testing.assert_allclose(w[ok], value[ok] / pdf[ok, None], rtol=1e-5, atol=1e-7)
    # a one-sided conductor is black from below: weight 0 there
    assert np.all(w[~above] == 0)
    # reflection, eta 1, the conductor's glossy reflection component
    assert np.all(np.asarray(bs.eta.numpy())[ok] == 1.0)
    types = np.asarray(bs.sampled_type.numpy())
    assert np.all(types[ok] == int(nested.flags(0)))
    # pdf is 0 across the surface for a disk model
    flipped = mi.Vector3f(np.ascontiguousarray((wo * np.float32([1, 1, -1])).T))
    assert np.all(np.asarray(bsdf.pdf(ctx, si, flipped).numpy())[ok] == 0)
    # eval and eval_pdf are the nested BSDF's value
    e, p = bsdf.eval_pdf(ctx, si, bs.wo)
    np.testing.assert_allclose(np.asarray(e.numpy()).T, value, rtol=1e-6)
    np.testing.assert_allclose(np.asarray(p.numpy()), again, rtol=1e-6)


def test_sample_conventions_transmissive_sphere(llvm, models):
    bsdf = mi.load_dict(learned(models, GLASS, "dielectric-beckmann-a0.3-sphere.dbsdf"))
    nested = mi.load_dict(GLASS)
    n = 4096
    wi = directions(n, 3, lower_fraction=0.5)
    u = np.random.default_rng(4).random((n, 2), dtype=np.float32)
    si = interaction(wi)
    ctx = mi.BSDFContext()
    bs, weight = bsdf.sample(ctx, si, mi.Float(np.zeros(n, np.float32)), mi.Point2f(np.ascontiguousarray(u.T)))
    wo = np.asarray(bs.wo.numpy()).T
    pdf = np.asarray(bs.pdf.numpy())
    eta = np.asarray(bs.eta.numpy())
    comp = np.asarray(bs.sampled_component.numpy())
    ok = pdf > 0
    trans = ok & (wo[:, 2] * wi[:, 2] < 0)
    refl = ok & (wo[:, 2] * wi[:, 2] > 0)
    assert trans.sum() > n // 4 and refl.sum() > 50
    np.testing.assert_allclose(eta[trans & (wi[:, 2] > 0)], 1.5, rtol=1e-6)
    np.testing.assert_allclose(eta[trans & (wi[:, 2] < 0)], 1 / 1.5, rtol=1e-6)
    assert np.all(eta[refl] == 1.0)
    assert np.all(comp[trans] == 1) and np.all(comp[refl] == 0)
    assert np.all(np.asarray(bs.sampled_type.numpy())[trans] == int(nested.flags(1)))
    value = np.asarray(nested.eval(ctx, si, bs.wo).numpy()).T
    w = np.asarray(weight.numpy()).T
    np.testing.assert_allclose(w[ok], value[ok] / pdf[ok, None], rtol=1e-5, atol=1e-7)


def test_bad_plugin_arguments(llvm, models):
    with pytest.raises(Exception, match="nested BSDF is required"):
        mi.load_dict({"type": "diffbsdf", "model": str(models / "conductor-ggx-a0.3-cu-disk.dbsdf")})
    with pytest.raises(Exception, match="model is required"):
        mi.load_dict({"type": "diffbsdf", "bsdf": CU})
    with pytest.raises(Exception, match="not found"):
        mi.load_dict({"type": "diffbsdf", "model": "no/such.dbsdf", "bsdf": CU})
    with pytest.raises(Exception, match="steps must be >= 1"):
        mi.load_dict(learned(models, CU, steps=0))


def test_scalar_variant(models):
    mi.set_variant("scalar_rgb")
    try:
        import diffbsdf.mitsuba_bsdf as dm

        dm.register()
        bsdf = mi.load_dict(learned(models, CU))
        model = diffbsdf.Model.load(models / "conductor-ggx-a0.3-cu-disk.dbsdf")
        si = dr.zeros(mi.SurfaceInteraction3f)
        si.wi = mi.Vector3f(0.6, 0.0, 0.8)
        bs, weight = bsdf.sample(mi.BSDFContext(), si, 0.5, mi.Point2f(0.3, 0.7))
        wo, pdf, valid = model.sample(np.float32([[0.6, 0.0, 0.8]]), np.float32([[0.3, 0.7]]))
        assert valid[0]
        np.testing.assert_allclose([bs.wo.x, bs.wo.y, bs.wo.z], wo[0], atol=1e-6)
        assert abs(bs.pdf - pdf[0]) <= 1e-6 * pdf[0]
        assert abs(bsdf.pdf(mi.BSDFContext(), si, bs.wo) - pdf[0]) <= 1e-4 * pdf[0]
        assert weight[0] > 0
        img = np.asarray(mi.render(mi.load_dict(_scene(learned(models, CU), "mis", 8, 6, 4)), seed=0))
        assert img.shape == (6, 8, 3) and np.all(np.isfinite(img)) and img.mean() > 0
    finally:
        mi.set_variant("llvm_ad_rgb")


def _scene(bsdf, mode, w, h, spp):
    from diffbsdf import scenes

    return scenes.object_scene(bsdf, mode, width=w, height=h, spp=spp)


def _renders(scene_dict, seeds):
    scene = mi.load_dict(scene_dict)
    return np.stack([np.asarray(mi.render(scene, seed=int(s)), dtype=np.float64) for s in seeds])


@pytest.mark.parametrize("mode", ["bsdf", "mis"])
def test_unbiased_in_a_rendered_scene(llvm, models, mode):
    """Sphere of rough copper on a ground plane under a procedural sky, Mitsuba's `direct`
    integrator; the learned sampler (BSDF sampling only, or with MIS) converges to the image
    of the nested BSDF's own sampler: per-block z-scores over independent renders."""
    from diffbsdf import scenes

    w, h, spp, renders = 32, 24, 8, 24
    ref = _renders(_scene(CU, mode, w, h, spp), range(renders))
    ours = _renders(_scene(learned(models, CU), mode, w, h, spp), range(1000, 1000 + renders))
    mask = scenes.object_mask(mi.load_dict(_scene(CU, mode, w, h, spp)), w, h)
    z = _block_z(ref, ours, mask)
    print(f"{mode}: {z.shape[0]} blocks, max |z| {np.max(np.abs(z)):.2f}, mean z^2 {np.mean(z**2):.2f}")
    assert z.shape[0] >= 20
    # 24 + 24 renders per block (t with ~46 dof): |z| > 4.5 has probability ~5e-5 per block
    assert np.max(np.abs(z)) < 4.5, np.round(z, 2)
    assert np.mean(z**2) < 2.0, np.mean(z**2)
    # the whole object: within 4 standard errors
    a, c = ref[:, mask].mean(axis=(1, 2)), ours[:, mask].mean(axis=(1, 2))
    z_all = (c.mean() - a.mean()) / np.sqrt((a.var(ddof=1) + c.var(ddof=1)) / renders)
    assert abs(z_all) < 4.0, z_all
    # power: the same test flags an image that is 10 % too dark
    assert np.max(np.abs(_block_z(ref, ours * 0.9, mask))) > 4.5


def _block_z(ref, ours, mask, b=4):
    """z-score of the mean difference per b x b block (object pixels, channels averaged)."""
    renders, h, w = ref.shape[:3]
    zs = []
    for by in range(0, h, b):
        for bx in range(0, w, b):
            m = mask[by : by + b, bx : bx + b]
            if m.sum() < 4:
                continue
            a = ref[:, by : by + b, bx : bx + b][:, m].mean(axis=(1, 2))  # (renders,)
            c = ours[:, by : by + b, bx : bx + b][:, m].mean(axis=(1, 2))
            se = np.sqrt(a.var(ddof=1) / renders + c.var(ddof=1) / renders)
            zs.append((c.mean() - a.mean()) / se)
    return np.asarray(zs)
