"""A C- or F-contiguous volume is read in place: meshing does not copy it (peak RSS)."""

import subprocess
import sys
import textwrap

import pytest


@pytest.mark.parametrize("order", ["C", "F"])
def test_contiguous_volume_is_not_copied(order):
    code = textwrap.dedent(
        f"""
        import resource, numpy as np, rdt_mesher
        n = 320  # 320^3 float32 = 125 MiB
        vol = np.zeros((n, n, n), dtype=np.float32, order="{order}")
        vol[100:220, 100:220, 100:220] = 1.0
        before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        m = rdt_mesher.mesh_image(vol, iso=0.5, size=12.0, verify=False)
        after = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        print(vol.nbytes >> 10, after - before, len(m.vertices))
        """
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    nbytes_kib, grew_kib, nv = map(int, r.stdout.split())
    assert nv > 0
    # A copy would add at least the array's size to the peak.
    assert grew_kib < nbytes_kib // 2, (grew_kib, nbytes_kib)
