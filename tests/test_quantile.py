"""Exact percentiles and medians (nfdepth._quantile) against NumPy's own, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from nfdepth import _quantile, fast


@pytest.fixture(params=["numba", "numpy"])
def backend(request, monkeypatch):
    """The compiled bracket pass and the NumPy-mask one."""
    if request.param == "numba" and not fast.USE_NUMBA:
        pytest.skip("numba not installed (or NFDEPTH_NO_NUMBA set)")
    monkeypatch.setattr(fast, "USE_NUMBA", request.param == "numba")
    return request.param


def _arrays(n, dtype, rng):
    ramp = np.arange(n, dtype=dtype)
    spiky = np.zeros(n, dtype)
    spiky[rng.integers(0, n, n // 50)] = rng.random(n // 50)  # 2 % non-zero: ties at 0 below the top
    with_inf = rng.random(n).astype(dtype)
    with_inf[::7] = np.inf
    return {
        "uniform": rng.random(n).astype(dtype),
        "exponential": rng.exponential(size=n).astype(dtype),
        "ties": np.round(rng.random(n) * 10).astype(dtype),
        "ramp": ramp,  # the subsample brackets a sorted array well
        "reversed": ramp[::-1].copy(),
        "spiky": spiky,
        "constant": np.zeros(n, dtype),
        "wide": (rng.standard_normal(n) * 1e6).astype(dtype),
        "with_inf": with_inf,
    }


QS = (0.0, 0.5, 1.0, 33.3, 50.0, 90.0, 99.0, 99.5, 99.99, 100.0)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("n", [4096, 5001, 306_081])
def test_matches_numpy_bit_for_bit(n, dtype, backend):
    rng = np.random.default_rng(n)
    # "with_inf": inf - inf in the interpolation warns in NumPy and here alike
    for name, a in _arrays(n, dtype, rng).items():
        for shaped in (a, a.reshape(-1, 1)):
            with np.errstate(invalid="ignore"):
                _check_all(name, shaped)


def _check_all(name, shaped):
    for q in QS:
        got, want = _quantile.percentile(shaped, q), np.percentile(shaped, q)
        assert type(got) is type(want), (name, q)
        assert np.array_equal(got, want, equal_nan=True), (name, q, got, want)
    got, want = _quantile.percentiles(shaped, [1, 99]), np.percentile(shaped, [1, 99])
    assert got.dtype == want.dtype and np.array_equal(got, want, equal_nan=True), name
    got, want = _quantile.median(shaped), np.median(shaped)
    assert type(got) is type(want) and np.array_equal(got, want, equal_nan=True), name


def test_the_bracket_is_used_and_a_miss_falls_back(backend):
    n = 65_536
    a = np.random.default_rng(0).random(n)
    assert _quantile._order_statistics(a, n // 2, n // 2 + 1) is not None
    # every subsampled value is 0 and the rest 1: the bracket [0, 0] cannot hold
    # the median, so the exact answer comes from NumPy
    stride = max(1, n // _quantile._SAMPLE) | 1
    b = np.ones(n)
    b[::stride] = 0.0
    assert _quantile._order_statistics(b, n // 2, n // 2 + 1) is None
    assert _quantile.percentile(b, 50.0) == np.percentile(b, 50.0) == 1.0
    assert _quantile.percentile(b, 1.0) == np.percentile(b, 1.0) == 0.0


def test_nan_small_and_other_dtypes_are_numpys(backend):
    rng = np.random.default_rng(1)
    a = rng.random(10_000)
    a[123] = np.nan
    assert np.isnan(_quantile.percentile(a, 50.0)) and np.isnan(_quantile.median(a))
    assert np.isnan(_quantile.percentiles(a, [1, 99])).all()
    small = rng.random(100).astype(np.float32)
    assert _quantile.percentile(small, 90.0) == np.percentile(small, 90.0)
    ints = rng.integers(0, 255, 10_000).astype(np.uint8)
    assert _quantile.percentile(ints, 90.0) == np.percentile(ints, 90.0)
    assert _quantile.median(ints) == np.median(ints)


@pytest.mark.parametrize("q", [-1.0, 100.5, float("nan")])
def test_a_percentile_outside_0_100_is_refused_as_numpy_does(q, backend):
    a = np.random.default_rng(2).random(10_000)
    with pytest.raises(ValueError, match="Percentiles must be in the range"):
        _quantile.percentile(a, q)
    with pytest.raises(ValueError, match="Percentiles must be in the range"):
        _quantile.percentiles(a, [1.0, q])


def test_nan_beyond_the_bracket_is_numpys(backend):
    """5 % NaN: np.partition puts them at the top of the subsample, so the bracket of a high
    percentile is NaN itself (the early fall-back); lower ones count past the NaN. Either way
    NumPy's answer: NaN."""
    a = np.random.default_rng(3).random(50_000)
    a[::20] = np.nan
    assert _quantile._order_statistics(a, int(0.99 * (a.size - 1)), int(0.99 * (a.size - 1)) + 1) is None
    for q in (99.0, 99.9, 50.0):
        assert np.isnan(_quantile.percentile(a, q)) and np.isnan(np.percentile(a, q))
    assert np.isnan(_quantile.percentiles(a, [1.0, 99.5])).all()
    assert np.isnan(_quantile.median(a))
