"""The worked example: every label meshed on a Dask local cluster equals the serial loop."""

import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "examples"))
import dask_labels  # noqa: E402


@pytest.mark.parametrize("processes", [True, False])
def test_dask_cluster_equals_serial_loop(processes):
    seg, affine = dask_labels.synthetic_segmentation(32)
    par = dask_labels.mesh_dask(seg, affine, 1.2, workers=2, processes=processes)
    ser = dask_labels.mesh_serial(seg, affine, 1.2)
    assert sorted(par) == sorted(ser) == dask_labels.labels_of(seg) and len(ser) >= 3
    for l in ser:
        assert np.array_equal(par[l][0], ser[l][0]) and np.array_equal(par[l][1], ser[l][1])
        assert len(ser[l][1]) > 0


def test_example_main_reports_identical(capsys):
    assert dask_labels.main(["--workers", "2", "--size", "1.5", "--threads"]) == 0
    assert "identical to the serial loop" in capsys.readouterr().out
