"""The reference materials from Python: construction, argument checks, sample/pdf
agreement, and a learned model against its target (albedo by importance sampling)."""

import pathlib

import numpy as np
import pytest

import diffbsdf
from diffbsdf import _diffbsdf

from test_model import COPPER, hemisphere_wi

CU_SPEC = "conductor:ggx,alpha=0.3,metal=Cu"
RGL_DIR = pathlib.Path(__file__).resolve().parents[3] / "shared" / "data" / "rgl"


def tile(w, n: int) -> np.ndarray:
    return np.ascontiguousarray(np.tile(np.float32(w), (n, 1)))


def incidence(theta_deg: float) -> np.ndarray:
    t = np.radians(theta_deg)
    return np.float32([np.sin(t), 0.0, np.cos(t)])


def uniforms3(n: int, seed: int) -> np.ndarray:
    return np.random.default_rng(seed).random((n, 3), dtype=np.float32)


@pytest.fixture(scope="module")
def cu():
    return diffbsdf.Material.from_spec(CU_SPEC)


# -- construction -------------------------------------------------------------------------


def test_from_spec_properties_and_errors(cu):
    assert cu.name == "conductor"
    assert cu.spec.startswith("conductor:ggx,alpha=0.3")
    assert cu.transmissive is False and cu.isotropic is True
    assert diffbsdf.Material.from_spec(cu.spec).spec == cu.spec
    glass = diffbsdf.Material.from_spec("dielectric:beckmann,alpha=0.3,eta=1.5")
    assert glass.transmissive is True
    assert "conductor" in repr(cu)
    with pytest.raises(ValueError, match="unknown material model `velvet`"):
        diffbsdf.Material.from_spec("velvet")
    with pytest.raises(ValueError, match="unknown metal"):
        diffbsdf.Material.from_spec("conductor:metal=Pb")
    with pytest.raises(ValueError, match="bad value"):
        diffbsdf.Material.from_spec("conductor:alpha=-1")
    with pytest.raises(TypeError):
        diffbsdf.Material.from_spec(3)  # type: ignore[arg-type]
    with pytest.raises(FileNotFoundError):
        diffbsdf.Material.rgl("no/such/file_rgb.bsdf")
    with pytest.raises(FileNotFoundError):
        diffbsdf.Material.from_spec("rgl:no/such/file_rgb.bsdf")


def test_rgl_file_is_not_a_blob(tmp_path):
    bad = tmp_path / "bad_rgb.bsdf"
    bad.write_bytes(b"tensor_file\0 but nothing after it")
    with pytest.raises(ValueError, match="RGL file"):
        diffbsdf.Material.rgl(bad)


@pytest.mark.skipif(not RGL_DIR.is_dir(), reason="RGL data not present")
def test_rgl_measured_material_samples_and_evaluates():
    path = sorted(RGL_DIR.glob("*_rgb.bsdf"))[0]
    m = diffbsdf.Material.rgl(path)
    assert m.name == "rgl"
    assert diffbsdf.Material.from_spec(f"rgl:{path}").spec == m.spec
    n = 2000
    wi = tile(incidence(40.0), n)
    wo, pdf, valid = m.sample(wi, uniforms3(n, 5))
    assert valid.mean() > 0.9
    np.testing.assert_allclose(m.pdf(wi[valid], wo[valid]), pdf[valid], rtol=1e-3)
    f = m.eval(wi[valid], wo[valid])
    assert f.shape == (valid.sum(), 3) and np.all(f >= 0) and np.all(np.isfinite(f))


# -- shapes and dtypes --------------------------------------------------------------------


def test_shape_and_dtype_errors(cu):
    wi = hemisphere_wi(8, 0)
    u = uniforms3(8, 0)
    with pytest.raises(ValueError, match=r"u: expected shape \(N, 3\)"):
        cu.sample(wi, u[:, :2])
    with pytest.raises(ValueError, match=r"wi: expected shape \(N, 3\)"):
        cu.eval(wi[:, :2], wi)
    with pytest.raises(ValueError, match=r"expected shape"):
        cu.pdf(wi[0], wi[0])
    with pytest.raises(ValueError, match="lengths differ"):
        cu.sample(wi, u[:7])
    with pytest.raises(ValueError, match="lengths differ"):
        cu.eval_luminance(wi, wi[:3])
    with pytest.raises(TypeError, match="dtype int64"):
        cu.pdf(wi.astype(np.int64), wi)
    with pytest.raises(TypeError, match="dtype bool"):
        cu.sample(wi, u > 0.5)
    with pytest.raises(TypeError):
        cu.eval(wi, wi, threads="2")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="threads"):
        cu.eval(wi, wi, threads=0)
    raw = cu._raw
    assert isinstance(raw, _diffbsdf.RawMaterial)
    with pytest.raises(TypeError, match="float32"):
        raw.pdf(wi.astype(np.float64), wi)
    with pytest.raises(TypeError, match="C-contiguous"):
        raw.pdf(np.asfortranarray(wi), wi)


def test_outputs_and_invalid_rows(cu):
    n = 6
    wi = tile(incidence(30.0), n)
    wo = hemisphere_wi(n, 1)
    f = cu.eval(wi, wo)
    y = cu.eval_luminance(wi, wo)
    p = cu.pdf(wi, wo)
    assert f.dtype == np.float32 and f.shape == (n, 3)
    assert y.dtype == np.float32 and y.shape == (n,)
    assert p.dtype == np.float32 and p.shape == (n,)
    np.testing.assert_allclose(y, f @ np.float32([0.2126, 0.7152, 0.0722]), rtol=1e-5)
    # f * cos: eval divided by |cos theta_o| is the BSDF, symmetric in a conductor.
    np.testing.assert_allclose(f / wo[:, 2:], cu.eval(wo, wi) / wi[:, 2:], rtol=1e-4)
    # NaN, zero, non-unit directions, u outside [0, 1] and wo below a BRDF: zero rows.
    bad = np.float32([[np.nan, 0, 1], [0, 0, 0], [0, 0, 2], [0, 0, -1]])
    good = tile([0, 0, 1], 4)
    assert np.all(cu.eval(good, bad) == 0) and np.all(cu.pdf(bad, good) == 0)
    u = np.float32([[0.5, 0.5, 0.5], [1.5, 0.5, 0.5], [0.5, np.nan, 0.5]])
    wo_s, pdf_s, valid = cu.sample(tile([0, 0, 1], 3), u)
    assert valid.tolist() == [True, False, False]
    assert np.all(wo_s[1:] == 0) and np.all(pdf_s[1:] == 0)
    # Every row is independent: one thread or many give the same arrays.
    wi_b, u_b = tile(incidence(50.0), 3000), uniforms3(3000, 2)
    for a, b in zip(cu.sample(wi_b, u_b, threads=1), cu.sample(wi_b, u_b, threads=4)):
        np.testing.assert_array_equal(a, b)


# -- agreement ----------------------------------------------------------------------------


def test_pdf_of_sampled_directions_equals_the_sampled_pdf(cu):
    n = 20000
    for theta in (10.0, 45.0, 80.0):
        wi = tile(incidence(theta), n)
        wo, pdf, valid = cu.sample(wi, uniforms3(n, int(theta)))
        assert valid.mean() > 0.8, theta
        np.testing.assert_allclose(np.linalg.norm(wo[valid], axis=1), 1.0, atol=1e-6)
        np.testing.assert_allclose(cu.pdf(wi[valid], wo[valid]), pdf[valid], rtol=1e-4)


def albedo(values: np.ndarray, pdf: np.ndarray, valid: np.ndarray):
    """Importance-sampling estimate of the albedo per column of ``values`` and its
    standard error; invalid samples count as 0 (the estimator stays unbiased)."""
    w = np.where(valid[:, None], values / np.where(valid, pdf, 1.0)[:, None], 0.0)
    w = w.astype(np.float64)
    return w.mean(axis=0), w.std(axis=0, ddof=1) / np.sqrt(len(w))


def test_learned_model_and_material_agree_on_the_albedo(models, cu):
    """Mean of f*cos/pdf over the learned model's samples vs over the material's own
    samples: both estimate the same albedo, so they agree within a few standard errors."""
    model = diffbsdf.Model.load(models / COPPER)
    n = 200_000
    rng = np.random.default_rng(11)
    for theta in (25.0, 65.0):
        wi = tile(incidence(theta), n)
        wo_l, pdf_l, valid_l = model.sample(wi, rng.random((n, 2), dtype=np.float32))
        wo_m, pdf_m, valid_m = cu.sample(wi, rng.random((n, 3), dtype=np.float32))
        # RGB and luminance columns.
        est_l, se_l = albedo(
            np.column_stack([cu.eval(wi, wo_l), cu.eval_luminance(wi, wo_l)]), pdf_l, valid_l
        )
        est_m, se_m = albedo(
            np.column_stack([cu.eval(wi, wo_m), cu.eval_luminance(wi, wo_m)]), pdf_m, valid_m
        )
        z = np.abs(est_l - est_m) / np.sqrt(se_l**2 + se_m**2)
        assert np.all(z < 4.0), (theta, est_l, est_m, se_l, se_m)
        # A real check: the estimates are precise and the albedo is a copper one.
        assert np.all(se_l < 0.01 * est_l) and np.all(se_m < 0.01 * est_m), (se_l, se_m)
        assert 0.5 < est_m[3] < 1.0 and est_m[0] > est_m[2], est_m
