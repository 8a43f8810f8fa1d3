"""Scratch arrays kept per thread from one call to the next.

A fresh page costs a page fault when it is first written (several
microseconds each on a virtual machine), and glibc hands large freed blocks
back to the kernel, so a function that allocates its temporaries anew pays
that on every call: on 640 x 480 views static stereo took about 13000
faults per call between other work, 15 % of its time. OpenCV's matchers
keep their buffers in the matcher object for the same reason; nfdepth's
functions keep them here, per thread, keyed by name, shape and dtype.

An array from :meth:`Scratch.empty` is uninitialised and is the caller's
only until its next request for the same key on the same thread: it must
never be part of a result. Each pool keeps at most ``max_arrays`` arrays
and ``max_bytes`` bytes per thread (least recently used go first; a request
larger than the budget is simply not kept).
"""

from __future__ import annotations

import threading

import numpy as np

__all__: list[str] = []


class Scratch:
    """Per-thread kept scratch arrays (see the module docstring)."""

    def __init__(self, *, max_arrays: int, max_bytes: int):
        self.max_arrays = int(max_arrays)
        self.max_bytes = int(max_bytes)
        self._local = threading.local()
        self._generation = 0  # bumped by forget()

    def _kept(self) -> dict:
        local = self._local
        if getattr(local, "generation", None) != self._generation:
            local.arrays = {}  # least recently used first
            local.generation = self._generation
        return local.arrays

    def empty(self, key: str, shape, dtype=np.float32) -> np.ndarray:
        """An uninitialised array of ``shape`` and ``dtype``: this thread's kept one for ``key`` if there is one."""
        shape = tuple(int(s) for s in shape)
        dtype = np.dtype(dtype)
        kept = self._kept()
        k = (key, shape, dtype.str)
        arr = kept.pop(k, None)
        if arr is None:
            arr = np.empty(shape, dtype)
            if arr.nbytes > self.max_bytes:
                return arr
            total = sum(a.nbytes for a in kept.values()) + arr.nbytes
            while kept and (len(kept) >= self.max_arrays or total > self.max_bytes):
                total -= kept.pop(next(iter(kept))).nbytes
        kept[k] = arr  # most recently used last
        return arr

    def forget(self) -> None:
        """Make every thread drop its kept arrays at its next request (memory measurements count them from scratch)."""
        self._generation += 1

    def kept_bytes(self) -> int:
        """Bytes the calling thread keeps."""
        return sum(a.nbytes for a in self._kept().values())


#: Static stereo's pool (its cost volume's strips and its per-level
#: measurement). At 640 x 480 a call's scratch is about 41 MB on its calling
#: thread; larger images keep at most this budget per thread.
STEREO = Scratch(max_arrays=48, max_bytes=48 << 20)
