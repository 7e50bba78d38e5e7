"""The committed fixture must be exactly what the extractor writes today."""

import json
import os

import numpy as np
import pytest

from loudscape_fixtures.song import FIXTURE_STEM, write_fixture

from test_ply import tiny_read

DATA = os.path.join(os.path.dirname(__file__), "..", "..", "data")


def _close(a, b, path="root"):
    if isinstance(a, dict):
        assert isinstance(b, dict) and a.keys() == b.keys(), path
        for key in a:
            _close(a[key], b[key], f"{path}.{key}")
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            _close(x, y, f"{path}[{i}]")
    elif isinstance(a, float) or isinstance(b, float):
        assert a == pytest.approx(b, rel=1e-5, abs=1e-5), path
    else:
        assert a == b, path


def test_committed_fixture_matches_a_fresh_run(tmp_path):
    committed_ply = os.path.join(DATA, FIXTURE_STEM + ".ply")
    committed_json = os.path.join(DATA, FIXTURE_STEM + ".expected.json")
    fresh_ply, fresh_json = write_fixture(str(tmp_path))
    _, committed_meta, committed_points = tiny_read(committed_ply)
    _, fresh_meta, fresh_points = tiny_read(fresh_ply)
    assert fresh_points.shape == committed_points.shape
    assert 100 <= fresh_points.shape[0] <= 1000
    np.testing.assert_allclose(fresh_points, committed_points, atol=1e-5)
    _close(fresh_meta, committed_meta)
    with open(committed_json) as a, open(fresh_json) as b:
        _close(json.load(b), json.load(a))


def test_expected_json_describes_the_committed_ply():
    _, metadata, points = tiny_read(os.path.join(DATA, FIXTURE_STEM + ".ply"))
    with open(os.path.join(DATA, FIXTURE_STEM + ".expected.json")) as handle:
        expected = json.load(handle)
    assert expected["point_count"] == points.shape[0] == metadata["point_count"]
    assert expected["first_records"] == points[:3].tolist()
    assert expected["last_records"] == points[-3:].tolist()
    np.testing.assert_allclose(expected["column_sums"], points.astype(np.float64).sum(axis=0))
    assert expected["metadata"] == metadata
