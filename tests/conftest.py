"""Test-suite configuration: reproducible property-based tests.

The property tests (``test_properties.py``) run under a Hypothesis profile
chosen by ``$HYPOTHESIS_PROFILE``:

* ``repeatable`` (default): derandomised, no example database -- every run of
  the suite (and CI) tries the same examples, so a red run is reproducible
  and a green one does not turn red by chance;
* ``explore``: random examples and the local example database -- for
  hunting new counterexamples (``HYPOTHESIS_PROFILE=explore
  python -m pytest tests/test_properties.py``).
"""

from __future__ import annotations

import os

import pytest
from hypothesis import settings

from nfdepth import datasets

settings.register_profile("repeatable", derandomize=True, database=None, print_blob=True)
settings.register_profile("explore", derandomize=False)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "repeatable"))


@pytest.fixture(scope="session")
def tsukuba():
    """The Tsukuba row (five views, truth at the third); skipped where the real data is absent."""
    try:
        return datasets.load_scene("tsukuba", datasets.data_root())
    except datasets.DataNotFoundError:
        pytest.skip("real data not found: set NFDEPTH_DATA or put it at ../shared/data")
