# Fixtures of the hamal Python suite (python/README.md, "Tests"): the public
# datasets (HAMAL_DATA_DIR, else ../shared/data beside the checkout; a test
# that needs a missing file is skipped and says which), and small worlds
# built in code so that most tests need no dataset.
import math
import os

import numpy as np
import pytest

import hamal


def dataset_or_skip(name):
    path = os.path.join(hamal.data_dir(), name)
    if not os.path.isfile(path):
        pytest.skip(f"dataset {name} not found in {hamal.data_dir()} (set HAMAL_DATA_DIR)")
    return path


def square_world(poses=12, information=None):
    """A robot driving a square, odometry between consecutive poses and one loop
    closure back to pose 0, with noise-free measurements offset by a known bias
    so that the optimum is not the initial guess."""
    info = np.diag([100.0, 100.0, 400.0]) if information is None else information
    rng = np.random.default_rng(7)
    truth = [hamal.Pose2(0, 0, 0)]
    for i in range(1, poses):
        turn = math.pi / 2 if i % 3 == 0 else 0.0
        truth.append(truth[-1].compose(hamal.Pose2(1.0, 0.0, turn)))
    g = hamal.Graph()
    for i in range(1, poses):
        z = truth[i - 1].between(truth[i]).vector() + rng.normal(0, 0.05, 3)
        g.add(hamal.between(hamal.x(i - 1), hamal.x(i), z, info))
    z = truth[-1].between(truth[0]).vector() + rng.normal(0, 0.05, 3)
    g.add(hamal.between(hamal.x(poses - 1), hamal.x(0), z, info))
    return g, truth


@pytest.fixture
def world():
    return square_world()
