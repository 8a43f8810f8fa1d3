"""Per-thread kept scratch arrays (nfdepth._scratch) and that static stereo's never leak into its results."""

import threading

import numpy as np
import pytest

from nfdepth import _scratch, fast
from nfdepth._scratch import Scratch
from nfdepth.stereo import static_stereo


def test_same_key_and_shape_gives_the_kept_array():
    pool = Scratch(max_arrays=4, max_bytes=1 << 20)
    a = pool.empty("a", (3, 4))
    assert a.shape == (3, 4) and a.dtype == np.float32
    assert pool.empty("a", (3, 4)) is a
    # another name, shape or dtype is another array
    assert pool.empty("b", (3, 4)) is not a
    assert pool.empty("a", (4, 3)) is not a
    assert pool.empty("a", (3, 4), np.int32).dtype == np.int32
    assert pool.kept_bytes() == 4 * 48


def test_least_recently_used_go_first():
    pool = Scratch(max_arrays=2, max_bytes=1 << 20)
    a, b = pool.empty("a", (8,)), pool.empty("b", (8,))
    assert pool.empty("a", (8,)) is a  # a is now the most recent
    pool.empty("c", (8,))  # evicts b
    assert pool.empty("a", (8,)) is a
    assert pool.empty("b", (8,)) is not b


def test_byte_budget():
    pool = Scratch(max_arrays=10, max_bytes=1000)
    a = pool.empty("a", (100,))  # 400 B
    b = pool.empty("b", (100,))
    pool.empty("c", (100,))  # 1200 B: a goes
    assert pool.kept_bytes() == 800
    assert pool.empty("b", (100,)) is b
    assert pool.empty("a", (100,)) is not a
    big = pool.empty("big", (1000,))  # beyond the budget: handed out, not kept
    assert pool.empty("big", (1000,)) is not big
    assert pool.kept_bytes() <= 1000


def test_forget_and_threads_keep_their_own():
    pool = Scratch(max_arrays=4, max_bytes=1 << 20)
    a = pool.empty("a", (5,))
    other = []
    t = threading.Thread(target=lambda: other.append(pool.empty("a", (5,))))
    t.start()
    t.join()
    assert other[0] is not a
    assert pool.empty("a", (5,)) is a
    pool.forget()
    assert pool.kept_bytes() == 0
    assert pool.empty("a", (5,)) is not a


def _views(shift, seed):
    rng = np.random.default_rng(seed)
    base = np.cumsum(np.cumsum(rng.normal(size=(288, 112)), 0), 1).astype(np.float32)
    base = 100.0 + 40.0 * (base - base.mean()) / base.std()
    cols = np.arange(112, dtype=np.float32)
    return [np.stack([np.interp(cols + k * shift, cols, row) for row in base]).astype(np.float32) for k in (-1, 0, 1)]


@pytest.mark.parametrize(("threads", "compiled"), [(1, True), (2, True), (1, False)])
def test_static_stereo_scratch_never_leaks_into_results(threads, compiled, monkeypatch):
    """A result is the same whatever ran before it, and later calls never change it.

    The cost volume's winner-take-all state and ``_measure``'s stacks are
    kept between calls; a stale state from another scene would change the
    winners, and an array shared with a result would be overwritten.
    """
    if not compiled:
        monkeypatch.setattr(fast, "USE_NUMBA", False)
    a_views, b_views = _views(1.5, 0), _views(4.0, 1)
    _scratch.STEREO.forget()
    fresh = static_stereo(a_views, reference=1, threads=threads)
    kept = {k: getattr(fresh, k).copy() for k in ("disparity", "uncertainty", "edge_mask", "reason")}
    assert np.isfinite(fresh.disparity).mean() > 0.5
    other = static_stereo(b_views, reference=1, threads=threads)
    assert not np.array_equal(other.disparity, fresh.disparity, equal_nan=True)
    again = static_stereo(a_views, reference=1, threads=threads)
    for k, v in kept.items():
        np.testing.assert_array_equal(getattr(fresh, k), v)  # unchanged by the later calls
        np.testing.assert_array_equal(getattr(again, k), v)  # the same after another scene
