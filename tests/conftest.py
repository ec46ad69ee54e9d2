"""Shared fixtures: the devices to test on (CPU always, CUDA when a GPU is present); the snapshot
store (warpbem/dynamics/snapshot_store.py) in a folder of each test's own, never the developer's."""

import numpy as np
import pytest

from warpbem import runtime
from warpbem.dynamics.snapshot_store import ENVIRONMENT


@pytest.fixture(scope="session", autouse=True)
def session_snapshot_store(tmp_path_factory):
    """The store of fixtures wider than a test (a module's runs), and of subprocesses they start;
    Warp's kernel cache stays where it is."""
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv(ENVIRONMENT, str(tmp_path_factory.mktemp("snapshot_store")))
        yield


@pytest.fixture(autouse=True)
def snapshot_store(tmp_path_factory, monkeypatch):
    """Each test's own store: a snapshot another test solved is not read, so a test's solves are its own."""
    folder = tmp_path_factory.mktemp("snapshot_store")
    monkeypatch.setenv(ENVIRONMENT, str(folder))
    return folder


def _devices():
    wp = runtime.init()
    return ["cpu"] + (["cuda:0"] if wp.is_cuda_available() else [])


@pytest.fixture(params=_devices())
def device(request):
    return request.param


@pytest.fixture
def rng():
    return np.random.default_rng(20261122)
