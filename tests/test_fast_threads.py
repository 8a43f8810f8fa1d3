"""The fast path on several threads: row strips give the one-thread results bit for bit."""

from __future__ import annotations

import itertools
import multiprocessing
import os
import signal
import threading
import time

import cv2
import numpy as np
import pytest
from test_fast import _sequence

from nfdepth import fast
from nfdepth.fast import StreamingNormalFlow, normal_flow_edges

needs_numba = pytest.mark.skipif(not fast.USE_NUMBA, reason="the row strips are the numba path's (numba not installed or NFDEPTH_NO_NUMBA set)")


def _assert_same_bits(got, want):
    for x, y in zip(got, want):
        np.testing.assert_array_equal(x, y)
    assert got.min_gradient == want.min_gradient


@needs_numba
@pytest.mark.parametrize("shape", [(259, 131), (200, 97), (130, 41)])
@pytest.mark.parametrize("kwargs", [{"sigma_px": 1.7}, {"sigma_px": 0.0, "border_px": 0}, {"sigma_px": 2.2, "stencil": "paper", "max_corner_ratio": 0.3}])
@pytest.mark.parametrize("min_pixels", [1024, 2])
def test_any_thread_count_gives_the_one_thread_bits(shape, kwargs, min_pixels, monkeypatch):
    # small strips on small images; min_pixels 2: strips of two rows, so that strip boundaries fall on every kind of row
    monkeypatch.setattr(fast, "_STRIP_MIN_PIXELS", min_pixels)
    frames = _sequence(shape, seed=shape[0])
    want = normal_flow_edges(frames, threads=1, **kwargs)  # held: its buffers are never reused
    assert want.mask.sum() > 100  # a real test: many edge points in every strip
    for threads in (2, 3, 7):
        assert len(fast._cell_strips(shape[0] - 1, shape[1] - 1, threads)) > 1
        _assert_same_bits(normal_flow_edges(frames, threads=threads, **kwargs), want)


@needs_numba
def test_strips_start_on_even_rows_and_cover_the_grid(monkeypatch):
    for h in (1, 2, 3, 5, 64, 127, 128, 479, 959):
        for threads in (1, 2, 3, 4, 16):
            strips = fast._cell_strips(h, 3, threads)
            assert strips[0][0] == 0 and strips[-1][1] == h
            assert all(a % 2 == 0 and b > a for a, b in strips)
            assert all(b == a2 for (_, b), (a2, _) in itertools.pairwise(strips))
            assert len(strips) <= threads
    monkeypatch.setattr(fast, "_STRIP_MIN_PIXELS", 2)
    assert len(fast._cell_strips(959, 3, 16)) == 16


def test_small_images_stay_on_one_thread():
    # waking a thread costs about what a strip of fewer pixels saves
    assert fast._cell_strips(479, 639, 2) == [(0, 240), (240, 479)]
    assert fast._cell_strips(479, 639, 8) == [(0, 240), (240, 479)]  # at most two strips of 2**17 px
    assert fast._cell_strips(199, 639, 4) == [(0, 199)]


@needs_numba
def test_a_stream_on_threads_gives_the_one_thread_bits():
    seq = _sequence((190, 75), n=6, seed=3)
    one, three = StreamingNormalFlow(sigma_px=1.5, threads=1), StreamingNormalFlow(sigma_px=1.5, threads=3)
    for f in seq:
        a, b = one.push(f), three.push(f)
        if a is None:
            assert b is None
        else:
            _assert_same_bits(b, a)


def test_default_threads_follow_opencv():
    old = cv2.getNumThreads()
    try:
        cv2.setNumThreads(3)
        assert fast._threads(None) == max(1, cv2.getNumThreads())
        cv2.setNumThreads(1)
        assert fast._threads(None) == 1
    finally:
        cv2.setNumThreads(old)


@pytest.mark.parametrize(("threads", "exc"), [(0, ValueError), (-2, ValueError), (1.5, TypeError), (True, TypeError), ("2", TypeError)])
def test_bad_thread_counts_are_refused(threads, exc):
    frames = _sequence((20, 24))
    with pytest.raises(exc, match=f"threads must be an integer >= 1, got {threads!r}"):
        normal_flow_edges(frames, sigma_px=1.0, threads=threads)
    with pytest.raises(exc, match="threads must be an integer >= 1"):
        StreamingNormalFlow(sigma_px=1.0, threads=threads)


def test_a_failing_strip_raises_once_every_started_strip_has_ended():
    started, ended = [], []
    lock = threading.Lock()

    def strip(i):
        with lock:
            started.append(i)
        if i == 1:
            msg = "strip 1 failed"
            raise RuntimeError(msg)
        time.sleep(0.05)
        with lock:
            ended.append(i)

    with pytest.raises(RuntimeError, match="strip 1 failed"):
        fast._run_strips(strip, 6, 3)
    assert 1 in started and sorted(ended) == sorted(i for i in started if i != 1)
    time.sleep(0.1)
    assert sorted(ended) == sorted(i for i in started if i != 1)  # nothing started after the return


class _Alarm(Exception):
    pass


def _interrupted_while_waiting(worker, **kwargs):
    """Two strips, ``worker()`` on the pool and an alarm armed by the caller's; ``_run_strips`` must raise the alarm.

    The alarm fires while the caller waits for the worker's strip.
    """
    main = threading.get_ident()
    worker_started = threading.Event()

    def strip(i):
        if threading.get_ident() == main:
            assert worker_started.wait(5.0)  # leaves the other strip to the worker
            signal.setitimer(signal.ITIMER_REAL, 0.05)  # fires while this thread waits for the worker
            return
        worker_started.set()
        worker()

    def alarm(signum, frame):
        raise _Alarm

    old = signal.signal(signal.SIGALRM, alarm)
    try:
        with pytest.raises(_Alarm):
            fast._run_strips(strip, 2, 2, **kwargs)
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


needs_setitimer = pytest.mark.skipif(not hasattr(signal, "setitimer"), reason="needs signal.setitimer (POSIX)")


@needs_setitimer
def test_an_interrupt_while_waiting_is_raised_once_the_running_strips_have_ended():
    # e.g. Ctrl-C while a worker still writes into the caller's buffers
    ended = []

    def worker():
        time.sleep(0.3)
        ended.append(1)

    _interrupted_while_waiting(worker)
    assert len(ended) == 1  # the worker's strip ended before the call returned


def test_a_failure_sets_stop_so_that_a_long_strip_ends_early():
    # static stereo's cost-volume strips poll ``stop`` between chunks of candidates
    stop = threading.Event()
    main = threading.get_ident()
    polled = []

    def strip(i):
        if threading.get_ident() == main:
            time.sleep(0.05)  # the worker is inside its long strip by now
            msg = "this strip failed"
            raise RuntimeError(msg)
        t0 = time.perf_counter()
        while not stop.is_set() and time.perf_counter() - t0 < 5.0:
            time.sleep(0.005)
        polled.append(time.perf_counter() - t0)

    t0 = time.perf_counter()
    with pytest.raises(RuntimeError, match="this strip failed"):
        fast._run_strips(strip, 2, 2, stop=stop)
    assert stop.is_set() and len(polled) == 1  # the worker's strip saw it and ended before the return
    assert time.perf_counter() - t0 < 2.0


@needs_setitimer
def test_an_interrupt_while_waiting_sets_stop():
    stop = threading.Event()

    def worker():
        assert stop.wait(5.0)  # a strip that would run for long without it

    t0 = time.perf_counter()
    _interrupted_while_waiting(worker, stop=stop)
    assert stop.is_set() and time.perf_counter() - t0 < 2.0


class _Interrupt(BaseException):  # as KeyboardInterrupt: no Exception
    pass


def test_an_interrupt_wins_over_a_strip_error():
    # Ctrl-C while numba compiles a kernel in the calling thread: the worker's
    # call of the half-compiled kernel fails ("no compiled object yet"), and the
    # user must see the interrupt, not an internal error
    main = threading.get_ident()
    worker_failed = threading.Event()

    def strip(i):
        if threading.get_ident() == main:
            assert worker_failed.wait(5.0)
            time.sleep(0.02)  # the worker's error is recorded first
            raise _Interrupt
        worker_failed.set()
        msg = "a consequence of the interrupt"
        raise RuntimeError(msg)

    with pytest.raises(_Interrupt):
        fast._run_strips(strip, 2, 2)


def test_the_caller_never_waits_for_a_worker_that_has_not_started():
    # An idle core can wake later than a strip takes: the caller claims every
    # strip left and returns, whatever the pool's workers are doing.
    release = threading.Event()
    fast._pool(2).submit(release.wait, 10)  # the pool's only worker is busy
    safety = threading.Timer(5.0, release.set)
    safety.start()
    try:
        runners = []
        t0 = time.perf_counter()
        fast._run_strips(lambda i: runners.append(threading.get_ident()), 5, 2)
        elapsed = time.perf_counter() - t0
    finally:
        release.set()
        safety.cancel()
    assert runners == [threading.get_ident()] * 5
    assert elapsed < 1.0


@needs_numba
@pytest.mark.skipif("fork" not in multiprocessing.get_all_start_methods(), reason="needs the fork start method (POSIX)")
@pytest.mark.filterwarnings("ignore:This process .* is multi-threaded:DeprecationWarning")
def test_a_forked_child_gets_its_own_pool():
    # The parent's pool threads do not exist in a forked child: it must not wait on them.
    frames = _sequence((200, 60), seed=9)
    want = normal_flow_edges(frames, sigma_px=1.5, threads=2)
    with multiprocessing.get_context("fork").Pool(1) as pool:
        got = pool.apply_async(_child_run, (frames,)).get(timeout=60)
    assert got[0] != os.getpid()
    for x, y in zip(got[1], want):
        np.testing.assert_array_equal(x, y)


def _child_run(frames):
    return os.getpid(), [np.array(x) for x in normal_flow_edges(frames, sigma_px=1.5, threads=2)]
