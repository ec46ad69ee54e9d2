"""Shared fixtures: the devices to test on (CPU always, CUDA when a GPU is present)."""

import numpy as np
import pytest

from warpbem import runtime


def _devices():
    wp = runtime.init()
    return ["cpu"] + (["cuda:0"] if wp.is_cuda_available() else [])


@pytest.fixture(params=_devices())
def device(request):
    return request.param


@pytest.fixture
def rng():
    return np.random.default_rng(20261122)
