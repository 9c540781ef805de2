import numpy as np
import pytest

from centrality_vision.datasets import load_face, load_fish


def rotation_2d(degrees):
    a = np.radians(degrees)
    return np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])


def rotation_3d(degrees, axis):
    axis = np.asarray(axis, dtype=float)
    axis = axis / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    a = np.radians(degrees)
    return np.eye(3) + np.sin(a) * k + (1 - np.cos(a)) * k @ k


@pytest.fixture(scope="session")
def fish():
    return load_fish().moving


@pytest.fixture(scope="session")
def fish_pair():
    return load_fish()


@pytest.fixture(scope="session")
def face():
    return load_face().moving


@pytest.fixture(scope="session")
def rot2():
    return rotation_2d


@pytest.fixture(scope="session")
def rot3():
    return rotation_3d
