"""voxfuse.Settings is the settings table (engines/PipelineSettings.h): every row a property with its
docstring, checked as the row says, and the same names and defaults as `voxfuse --help`."""

import os
import re
import subprocess
import warnings

import pytest

import voxfuse


def test_every_row_is_a_property_with_its_default_and_help():
    table = voxfuse.Settings.table()
    names = [row["name"] for row in table]
    assert names == list(voxfuse.Settings().to_dict()), "to_dict holds the table's settings, in its order"
    defaults = voxfuse.Settings()
    for row in table:
        assert getattr(defaults, row["name"]) == row["default"], row["name"]
        doc = getattr(voxfuse.Settings, row["name"]).__doc__
        assert row["help"] in doc and repr(row["default"]) in doc, row["name"]
        assert row["option"] == "--" + row["name"].replace("_", "-")
    assert defaults.voxel_size == 0.005, "floats read back as the decimals they are"


def test_values_are_checked_as_the_row_says():
    with pytest.raises(voxfuse.ConfigError, match=r"setting 'voxel_size': 0 is not in \(0, 1\]"):
        voxfuse.Settings(voxel_size=0)
    with pytest.raises(voxfuse.ConfigError, match="is not in"):
        voxfuse.Settings(max_depth=1e39)  # infinite as a float
    with pytest.raises(voxfuse.ConfigError, match="is not in"):
        voxfuse.Settings(relocalise_max_speed=float("nan"))
    with pytest.raises(voxfuse.ConfigError, match="'octree' is not one of hash, dense"):
        voxfuse.Settings(index="octree")
    with pytest.raises(voxfuse.ConfigError, match="takes 3 numbers, not 2"):
        voxfuse.Settings(volume_size=[64, 64])
    with pytest.raises(voxfuse.ConfigError, match="out of range"):
        voxfuse.Settings(max_weight=2**40)
    with pytest.raises(TypeError, match="setting 'swap' cannot be 1 \\(a bool"):
        voxfuse.Settings(swap=1)
    with pytest.raises(TypeError, match="setting 'max_weight' cannot be True"):
        voxfuse.Settings(max_weight=True)
    with pytest.raises(TypeError, match="setting 'tracker_iterations' cannot be '10'"):
        voxfuse.Settings(tracker_iterations="10")
    s = voxfuse.Settings()
    with pytest.raises(voxfuse.ConfigError):
        s.mu = -1.0
    assert s.mu == 0.02, "a refused value leaves the setting as it was"
    import numpy as np
    s.max_weight = np.int64(50)
    s.tracker_max_distance = (0.1, 0.05, np.float32(0.02))
    assert s.max_weight == 50 and s.tracker_max_distance == [0.1, 0.05, 0.02]


def test_the_former_spelling_warns_and_sets_the_same_setting():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        s = voxfuse.Settings(relocalise_min_colour_correlation=0.25)
    assert s.relocalise_min_color_correlation == 0.25
    assert any(issubclass(w.category, DeprecationWarning) for w in caught)


def test_the_command_line_offers_the_same_settings_with_the_same_defaults():
    cli = os.environ.get("VOXFUSE_CLI")
    if not cli:
        pytest.skip("VOXFUSE_CLI (the voxfuse program) is not set; ctest sets it")
    help_text = subprocess.run([cli, "--help"], check=True, capture_output=True, text=True).stdout
    for row in voxfuse.Settings.table():
        match = re.search(r"^\s*" + re.escape(row["option"]) + r"(?=\s)([^\n]*)", help_text, re.M)
        assert match, row["option"] + " is not in voxfuse --help"
        shown = re.search(r"=(\S+)", match.group(1))
        default = row["default"]
        if row["type"] == "bool" or default in ("", []):
            continue
        assert shown, row["option"] + " shows no default"
        value = shown.group(1)
        if isinstance(default, list):
            assert [float(v) for v in value.strip("[]").split(",")] == pytest.approx(default), row["option"]
        elif isinstance(default, str):
            assert value == default, row["option"]
        else:
            assert float(value) == pytest.approx(default, rel=1e-6), row["option"]
