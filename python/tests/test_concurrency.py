"""Concurrent calls and thread counts give identical meshes; the GIL is released."""

import threading
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np

import rdt_mesher
from conftest import ball_volume


def run(vol, threads=None):
    return rdt_mesher.mesh_image(vol, iso=0.0, size=1.2, threads=threads)


def test_thread_pool_calls_are_identical():
    vol = ball_volume(40, 14.0)
    ref = run(vol)
    with ThreadPoolExecutor(max_workers=4) as ex:
        outs = list(ex.map(lambda _: run(vol, threads=1), range(6)))
    for m in outs:
        assert np.array_equal(m.vertices, ref.vertices)
        assert np.array_equal(m.faces, ref.faces)


def test_thread_count_does_not_change_the_mesh():
    vol = ball_volume(40, 14.0)
    a, b = run(vol, threads=1), run(vol, threads=2)
    assert np.array_equal(a.vertices, b.vertices)


def test_the_gil_is_released_while_meshing():
    vol = ball_volume(64, 24.0)
    ticks = []
    stop = threading.Event()

    def tick():
        while not stop.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.005)

    t = threading.Thread(target=tick)
    t.start()
    t0 = time.perf_counter()
    rdt_mesher.mesh_image(vol, iso=0.0, size=0.6)
    t1 = time.perf_counter()
    stop.set()
    t.join()
    inside = [x for x in ticks if t0 < x < t1]
    # The ticker ran during the call (it could not if the GIL were held).
    assert len(inside) >= 0.5 * (t1 - t0) / 0.005 * 0.2


def test_progress_callback_sees_meshing_and_verifying():
    vol = ball_volume(48, 18.0)
    events = []
    rdt_mesher.mesh_image(vol, iso=0.0, size=0.8, progress=events.append)
    stages = {e["stage"] for e in events}
    assert "verifying" in stages
    assert all(e["sample_points"] >= 0 for e in events if e["stage"] == "meshing")
