"""The docstring examples run and print what they say."""

import doctest
import importlib

import pytest

MODULES = ["nfdepth.normal_flow", "nfdepth.camera", "nfdepth.depth", "nfdepth.fast"]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    module = importlib.import_module(name)
    failures, attempted = doctest.testmod(module, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert attempted > 0, f"{name} has no docstring examples to run"
    assert failures == 0
