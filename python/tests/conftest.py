import os
import pathlib

import numpy as np
import pytest

import voxfuse

REPO = pathlib.Path(__file__).resolve().parents[2]
SYNTHETIC_ROOM = REPO / "data" / "synthetic_room"
SHARED_DATA = REPO.parent / "shared" / "data"


@pytest.fixture(scope="session")
def room_frames():
    """The first 12 frames of the bundled synthetic room (with ground truth), decoded once."""
    source = voxfuse.open_source(str(SYNTHETIC_ROOM), labels=str(SYNTHETIC_ROOM / "labels.txt"))
    frames = []
    for frame in source:
        frames.append(frame)
        if len(frames) == 12:
            break
    return source, frames


@pytest.fixture
def room_source():
    return voxfuse.open_source(str(SYNTHETIC_ROOM))


def rss_mb():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def first_world_pose(frames):
    """Ground-truth poses re-expressed relative to the first frame (the world of a tracked run)."""
    T0_inv = np.linalg.inv(frames[0].ground_truth_pose)
    return [T0_inv @ f.ground_truth_pose for f in frames]
