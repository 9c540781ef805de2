"""Every warning names the line of the caller's code, however deep in the package it is raised
(a fixed stacklevel named a line of the package behind a decorator or a meta-estimator)."""

import warnings

import numpy as np
import pytest

from centrality_vision.matching import match, mwme_match
from centrality_vision.registration import GPD, ICP, MultiscaleCPD, RigidCPD, estimate_normals

_OCTAGON = np.c_[np.cos(np.arange(8) * np.pi / 4), np.sin(np.arange(8) * np.pi / 4)]
_CLOUD = np.random.default_rng(0).random((40, 3))
_POINT = np.zeros((5, 3))  # one fixed point, repeated: a CollapseWarning


@pytest.mark.parametrize(
    "call",
    [
        lambda: mwme_match(_OCTAGON[::-1] * 2, _OCTAGON),  # behind renamed_parameters
        lambda: match(_OCTAGON[::-1] * 2, _OCTAGON, method="mwme"),  # two decorated calls deep
        lambda: estimate_normals(np.repeat(_CLOUD[:5], 3, axis=0), n_neighbors=3),
        lambda: estimate_normals(_CLOUD, k=5),  # the FutureWarning of the decorator itself
        lambda: ICP(k_normals=5, metric="point_to_plane").fit(_CLOUD, _CLOUD + 0.01),
        lambda: RigidCPD().fit(_CLOUD, _POINT),
        lambda: GPD(RigidCPD(max_iter=2), graph="knn").fit(_CLOUD, _CLOUD[::-1] + 0.1),  # stops at max_iter
        lambda: MultiscaleCPD(RigidCPD(), sizes=(20, 40)).fit(_CLOUD, _POINT),
    ],
    ids=["mwme_match", "match", "estimate_normals", "renamed", "ICP", "RigidCPD", "GPD", "MultiscaleCPD"],
)
def test_a_warning_names_the_callers_line(call):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        call()
    assert caught, "the call should warn"
    assert {w.filename for w in caught} == {__file__}, [(w.filename, str(w.message)[:60]) for w in caught]
