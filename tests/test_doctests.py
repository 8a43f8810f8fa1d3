"""The docstring examples run and print what they say."""

import doctest
import importlib

import pytest

MODULES = ["nfdepth.normal_flow", "nfdepth.camera", "nfdepth.depth", "nfdepth.edges", "nfdepth.pipelines", "nfdepth.io"]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    module = importlib.import_module(name)
    failures, _ = doctest.testmod(module, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert failures == 0
