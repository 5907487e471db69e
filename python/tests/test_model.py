"""The numpy batch API: loading, properties, argument checks, agreement, threads, steps."""

import threading

import numpy as np
import pytest

import diffbsdf
from diffbsdf import _diffbsdf

COPPER = "conductor-ggx-a0.3-cu-disk.dbsdf"
GLASS = "dielectric-beckmann-a0.3-sphere.dbsdf"


def hemisphere_wi(n: int, seed: int, lower: bool = False) -> np.ndarray:
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    v[:, 2] = np.abs(v[:, 2]) + 0.05
    if lower:
        v[:, 2] *= -1
    return np.ascontiguousarray((v / np.linalg.norm(v, axis=1, keepdims=True)).astype(np.float32))


def sphere_wi(n: int, seed: int) -> np.ndarray:
    v = np.random.default_rng(seed).normal(size=(n, 3))
    return np.ascontiguousarray((v / np.linalg.norm(v, axis=1, keepdims=True)).astype(np.float32))


def uniforms(n: int, seed: int) -> np.ndarray:
    return np.random.default_rng(seed).random((n, 2), dtype=np.float32)


@pytest.fixture(scope="module")
def copper(models):
    return diffbsdf.Model.load(models / COPPER)


@pytest.fixture(scope="module")
def glass(models):
    return diffbsdf.Model.load(models / GLASS)


# -- loading and the model definition ----------------------------------------------------


def test_load_path_str_and_bytes_agree(models, copper):
    by_str = diffbsdf.Model.load(str(models / COPPER))
    by_bytes = diffbsdf.Model.load((models / COPPER).read_bytes())
    by_bytearray = diffbsdf.Model.load(bytearray((models / COPPER).read_bytes()))
    wi, u = hemisphere_wi(64, 1), uniforms(64, 2)
    ref = copper.sample(wi, u)
    for m in (by_str, by_bytes, by_bytearray):
        for a, b in zip(m.sample(wi, u), ref):
            np.testing.assert_array_equal(a, b)


def test_definition_properties(copper, glass, models):
    assert copper.domain == "disk"
    assert copper.default_steps == 4
    assert copper.isotropic is True
    assert copper.precision == "f32"
    assert copper.name == "conductor-ggx-a0.3-cu-disk"
    assert copper.shape == ((3, 16, 1), (5, 32, 3))
    assert glass.domain == "sphere"
    assert glass.default_steps == 8
    assert glass.shape[1] == (5, 32, 4)
    assert copper.incident_range == "upper_hemisphere"
    assert glass.incident_range == "whole_sphere"
    cu_sphere = diffbsdf.Model.load(models / "conductor-ggx-a0.3-cu-sphere.dbsdf")
    assert cu_sphere.incident_range == "upper_hemisphere"
    below = np.array([[0.3, 0.1, -0.9]], dtype=np.float32)
    below /= np.linalg.norm(below, axis=1, keepdims=True)
    wo, pdf, valid = cu_sphere.sample(below, np.array([[0.3, 0.6]], dtype=np.float32))
    assert not valid[0] and pdf[0] == 0
    half = diffbsdf.Model.load(models / "conductor-ggx-a0.3-cu-disk.f16.dbsdf")
    assert half.precision == "f16"
    assert "conductor-ggx-a0.3-cu-disk" in repr(copper)


def test_bad_blobs_raise_blob_format_error(models):
    good = (models / COPPER).read_bytes()
    with pytest.raises(diffbsdf.BlobFormatError, match="magic"):
        diffbsdf.Model.load(b"not a blob at all, not at all")
    with pytest.raises(diffbsdf.BlobFormatError):
        diffbsdf.Model.load(good[:-10])
    corrupt = bytearray(good)
    corrupt[200] ^= 0xFF
    with pytest.raises(diffbsdf.BlobFormatError):
        diffbsdf.Model.load(bytes(corrupt))
    assert issubclass(diffbsdf.BlobFormatError, ValueError)
    with pytest.raises(TypeError):
        diffbsdf.Model.load(42)  # type: ignore[arg-type]
    with pytest.raises(OSError):
        diffbsdf.Model.load(models / "no-such-model.dbsdf")


# -- shapes and dtypes -----------------------------------------------------------------


def test_shape_errors(copper):
    wi, u = hemisphere_wi(8, 0), uniforms(8, 0)
    with pytest.raises(ValueError, match=r"wi: expected shape \(N, 3\)"):
        copper.sample(wi[:, :2], u)
    with pytest.raises(ValueError, match=r"u: expected shape \(N, 2\)"):
        copper.sample(wi, np.zeros((8, 3), np.float32))
    with pytest.raises(ValueError, match=r"expected shape"):
        copper.pdf(wi[0], wi[0])
    with pytest.raises(ValueError, match="lengths differ"):
        copper.sample(wi, u[:7])
    with pytest.raises(ValueError, match="lengths differ"):
        copper.pdf(wi, wi[:3])
    with pytest.raises(ValueError, match=r"wo: expected shape"):
        copper.pdf(wi, np.zeros((8, 3, 1), np.float32))


def test_dtype_errors(copper):
    wi, u = hemisphere_wi(8, 0), uniforms(8, 0)
    with pytest.raises(TypeError, match="dtype int64"):
        copper.sample(wi.astype(np.int64), u)
    with pytest.raises(TypeError, match="dtype bool"):
        copper.sample_direction(wi, u > 0.5)
    with pytest.raises(TypeError, match="complex"):
        copper.pdf(wi.astype(np.complex64), wi)
    with pytest.raises(TypeError):
        copper.sample(wi, u, steps=2.5)  # type: ignore[arg-type]
    with pytest.raises(TypeError):
        copper.sample(wi, u, threads="2")  # type: ignore[arg-type]


def test_float32_c_contiguous_is_used_in_place_others_converted_once(copper):
    wi, u = hemisphere_wi(100, 3), uniforms(100, 4)
    assert diffbsdf.as_rows(wi, 3, "wi") is wi
    ref = copper.sample(wi, u)
    # float64, a Fortran-ordered copy, a strided view and a nested list convert to the same.
    strided = np.zeros((100, 6), np.float32)
    strided[:, ::2] = wi
    for variant in (wi.astype(np.float64), np.asfortranarray(wi), strided[:, ::2], wi.tolist()):
        for a, b in zip(copper.sample(variant, u), ref):
            np.testing.assert_array_equal(a, b)


def test_raw_module_is_strict(copper):
    """The extension itself never copies: only C-contiguous float32 (N, k) arrays pass."""
    raw = copper._raw
    wi, u = hemisphere_wi(8, 0), uniforms(8, 0)
    with pytest.raises(TypeError, match="float32"):
        raw.sample(wi.astype(np.float64), u)
    with pytest.raises(TypeError, match="C-contiguous"):
        raw.sample(np.asfortranarray(wi), u)
    with pytest.raises(TypeError, match="numpy array"):
        raw.pdf([[0.0, 0.0, 1.0]], [[0.0, 0.0, 1.0]])
    with pytest.raises(ValueError, match="shape"):
        raw.pdf(wi.reshape(-1), wi.reshape(-1))


def test_outputs_types_and_empty_batch(copper):
    wo, pdf, valid = copper.sample(np.zeros((0, 3), np.float32), np.zeros((0, 2), np.float32))
    assert wo.shape == (0, 3) and pdf.shape == (0,) and valid.shape == (0,)
    wi, u = hemisphere_wi(10, 0), uniforms(10, 1)
    wo, pdf, valid = copper.sample(wi, u)
    assert wo.dtype == np.float32 and pdf.dtype == np.float32 and valid.dtype == np.bool_
    assert wo.shape == (10, 3) and pdf.shape == (10,) and valid.shape == (10,)
    wo2, valid2 = copper.sample_direction(wi, u)
    assert wo2.dtype == np.float32 and valid2.dtype == np.bool_
    assert copper.pdf(wi, wo).dtype == np.float32


# -- agreement with the kernel ---------------------------------------------------------


@pytest.mark.parametrize(
    "name",
    [COPPER, "rgl-vch-golden-yellow-disk.dbsdf", "conductor-ggx-a0.3-cu-sphere.dbsdf", "rgl-vch-golden-yellow-hv.dbsdf"],
)
def test_pdf_of_sample_equals_sampled_pdf(models, name):
    m = diffbsdf.Model.load(models / name)
    n = 20000
    wi, u = hemisphere_wi(n, 5), uniforms(n, 6)
    wo, pdf, valid = m.sample(wi, u)
    assert valid.mean() > 0.9
    again = m.pdf(wi, wo)
    rel = np.abs(again[valid] - pdf[valid]) / pdf[valid]
    assert rel.max() <= 1e-4, rel.max()
    # invalid rows are zeros, valid rows are unit vectors on the sampled side
    assert np.all(wo[~valid] == 0) and np.all(pdf[~valid] == 0)
    np.testing.assert_allclose(np.linalg.norm(wo[valid], axis=1), 1.0, atol=1e-5)
    if m.domain in ("disk", "half-vector"):
        assert np.all(wo[valid, 2] >= 0)


def test_pdf_agreement_on_transmissive_sphere_model(glass):
    n = 20000
    wi, u = sphere_wi(n, 7), uniforms(n, 8)
    wo, pdf, valid = glass.sample(wi, u)
    again = glass.pdf(wi, wo)
    rel = np.abs(again[valid] - pdf[valid]) / pdf[valid]
    # models/README.md: a few tail samples (about 2e-5 of them) lose the Newton inversion
    assert np.mean(rel > 1e-4) < 1e-3
    assert np.any(wo[valid, 2] * wi[valid, 2] < 0), "transmission is sampled"


def test_sample_direction_matches_sample_and_pdf_integrates_to_at_most_one(copper):
    n = 4096
    wi, u = hemisphere_wi(n, 9), uniforms(n, 10)
    wo, pdf, valid = copper.sample(wi, u)
    wo2, valid2 = copper.sample_direction(wi, u)
    np.testing.assert_array_equal(valid, valid2)
    np.testing.assert_allclose(wo2, wo, atol=1e-6)
    # Monte Carlo integral of the pdf over the hemisphere (uniform directions): <= 1 (lost
    # mass is never renormalised) and close to the valid fraction.
    m = 200000
    w = np.tile(np.float32([0.5, 0.0, np.sqrt(0.75)]), (m, 1))
    d = hemisphere_wi(m, 11)
    z = np.random.default_rng(12).random(m)
    phi = np.random.default_rng(13).random(m) * 2 * np.pi
    r = np.sqrt(1 - z * z)
    d = np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1).astype(np.float32)
    integral = float(np.mean(copper.pdf(w, d)) * 2 * np.pi)
    frac_valid = float(np.mean(copper.sample(w[:20000], uniforms(20000, 14))[2]))
    assert abs(integral - frac_valid) < 0.03, (integral, frac_valid)


def test_invalid_inputs_give_invalid_rows(copper):
    wi = np.float32([[0, 0, 1], [0, 0, -1], [np.nan, 0, 1], [0, 0, 0], [0.6, 0, 0.8]])
    u = np.float32([[0.5, 0.5], [0.5, 0.5], [0.5, 0.5], [0.5, 0.5], [2.0, 0.5]])
    wo, pdf, valid = copper.sample(wi, u)
    assert valid.tolist() == [True, False, False, False, False]
    assert np.all(np.isfinite(wo)) and np.all(np.isfinite(pdf))
    assert np.all(copper.pdf(wi, np.tile(np.float32([0, 0, 1]), (5, 1)))[1:4] == 0)


# -- threads -------------------------------------------------------------------------


def test_threads_give_identical_results(copper, glass):
    n = 10007  # not a multiple of any thread count
    wi, u = hemisphere_wi(n, 15), uniforms(n, 16)
    for m in (copper, glass):
        one = m.sample(wi, u, threads=1)
        wo1 = m.pdf(wi, one[0], threads=1)
        d1 = m.sample_direction(wi, u, threads=1)
        for t in (2, 3, 8, None):
            for a, b in zip(m.sample(wi, u, threads=t), one):
                np.testing.assert_array_equal(a, b)
            np.testing.assert_array_equal(m.pdf(wi, one[0], threads=t), wo1)
            for a, b in zip(m.sample_direction(wi, u, threads=t), d1):
                np.testing.assert_array_equal(a, b)
    assert diffbsdf.available_threads() >= 1
    with pytest.raises(ValueError, match="threads"):
        copper.sample(wi, u, threads=0)
    reference = copper.sample(wi, u, threads=1)
    copper.threads = 3
    try:
        for a, b in zip(copper.sample(wi, u), reference):
            np.testing.assert_array_equal(a, b)
    finally:
        copper.threads = None


def test_gil_is_released_during_a_batch(copper):
    n = 100000
    wi, u = hemisphere_wi(n, 17), uniforms(n, 18)
    ticks = []
    stop = threading.Event()

    def ticker():
        while not stop.is_set():
            ticks.append(1)
            stop.wait(0.001)

    t = threading.Thread(target=ticker)
    t.start()
    try:
        copper.pdf(wi, wi, threads=1)
    finally:
        stop.set()
        t.join()
    assert len(ticks) > 5, "another Python thread ran while the batch was computed"


# -- steps -----------------------------------------------------------------------------


def test_steps_handling(copper):
    n = 4096
    wi, u = hemisphere_wi(n, 19), uniforms(n, 20)
    default = copper.sample(wi, u)
    for a, b in zip(copper.sample(wi, u, steps=copper.default_steps), default):
        np.testing.assert_array_equal(a, b)
    for a, b in zip(copper.sample(wi, u, steps=np.int64(4)), default):
        np.testing.assert_array_equal(a, b)
    wo8, pdf8, v8 = copper.sample(wi, u, steps=8)
    assert not np.array_equal(wo8, default[0])
    # at or above the default step count the PDF stays exact for the steps it was run with
    again = copper.pdf(wi, wo8, steps=8)
    assert np.max(np.abs(again[v8] - pdf8[v8]) / pdf8[v8]) <= 1e-4
    for bad in (0, -1, diffbsdf.MAX_STEPS + 1):
        for call in (
            lambda: copper.sample(wi, u, steps=bad),
            lambda: copper.sample_direction(wi, u, steps=bad),
            lambda: copper.pdf(wi, wo8, steps=bad),
        ):
            with pytest.raises(ValueError, match="steps must be >= 1"):
                call()
    with pytest.raises(TypeError):
        copper.sample(wi, u, steps=True)  # type: ignore[arg-type]
