"""GL backend selection. PyOpenGL binds its platform once per process, so every case runs in a
fresh Python subprocess."""

import json
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from cadsim.render.backend import BACKENDS, _missing_libraries

pytestmark = pytest.mark.render


def run_py(code: str, **env) -> subprocess.CompletedProcess:
    full_env = {
        k: v for k, v in os.environ.items() if k not in ("CADSIM_GL_BACKEND", "PYOPENGL_PLATFORM")
    }
    full_env.update(env)
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        capture_output=True,
        text=True,
        env=full_env,
        timeout=120,
    )


def test_unknown_backend_name_is_rejected_with_the_choices():
    res = run_py(
        """
        from cadsim.render import select_backend
        select_backend()
        """,
        CADSIM_GL_BACKEND="vulkan9",
    )
    assert res.returncode != 0
    assert "RuntimeError" in res.stderr and "'vulkan9'" in res.stderr
    assert "osmesa, egl" in res.stderr


def test_missing_library_names_it_and_the_install_command():
    res = run_py(
        """
        import cadsim.render.backend as b
        b.BACKENDS["osmesa"] = b.BackendSpec("osmesa", (("libOSMesa_missing.so.99",),), ("libosmesa6",))
        try:
            b.select_backend()
        except RuntimeError as e:
            print("ERR", e)
        import os, sys
        print("PLATFORM", os.environ.get("PYOPENGL_PLATFORM"), "OpenGL" in sys.modules)
        """,
        CADSIM_GL_BACKEND="osmesa",
    )
    assert res.returncode == 0, res.stderr
    assert "libOSMesa_missing.so.99" in res.stdout
    assert "apt-get install -y libosmesa6" in res.stdout
    assert "PLATFORM None False" in res.stdout  # nothing was bound on failure


def test_all_backends_missing_lists_each_with_its_packages():
    res = run_py(
        """
        import cadsim.render.backend as b
        b.BACKENDS = {k: b.BackendSpec(k, (("libnothing_%s.so.1" % k,),), v.apt_packages) for k, v in b.BACKENDS.items()}
        from cadsim.render import Renderer
        Renderer(64, 48)
        """
    )
    assert res.returncode != 0
    assert "libnothing_osmesa.so.1" in res.stderr and "libnothing_egl.so.1" in res.stderr
    assert "libosmesa6" in res.stderr and "libegl1" in res.stderr


def test_automatic_choice_prefers_osmesa_and_sets_the_platform_before_opengl():
    res = run_py(
        """
        import sys
        from cadsim.render import select_backend
        assert "OpenGL" not in sys.modules
        name = select_backend()
        import os
        print(name, os.environ["PYOPENGL_PLATFORM"])
        """
    )
    assert res.returncode == 0, res.stderr
    expected = next(k for k in BACKENDS if not _missing_libraries(BACKENDS[k]))
    assert res.stdout.split() == [expected, expected]


RENDER_WALL = """
import json, numpy as np
from cadsim.camera import Camera
from cadsim.render import Renderer
from cadsim.world import Snapshot, WorldObject
wall = WorldObject("w", "building", "building", (10.2, 0.0, 3.0), 0.0, (0.4, 30.0, 6.0), (0.6, 0.6, 0.6), target=False)
car = WorldObject("c", "car", "car", (7.0, 1.0, 0.75), 0.6, (4.5, 1.8, 1.5), (0.8, 0.1, 0.1))
r = Renderer(160, 120)
v = r.render(Snapshot(0.0, [wall, car]), Camera((0.0, 0.0, 1.6), 0.0, width=160, height=120))
print(json.dumps({"backend": r.backend, "depth": v.depth.tolist(), "instance": v.instance.tolist()}))
"""


def test_both_backends_render_exact_depth_and_identical_instances():
    available = [b for b in BACKENDS if not _missing_libraries(BACKENDS[b])]
    if not available:
        pytest.skip("no GL backend libraries installed")
    results = {}
    for backend in available:
        res = run_py(RENDER_WALL, CADSIM_GL_BACKEND=backend)
        assert res.returncode == 0, res.stderr
        out = json.loads(res.stdout.strip().splitlines()[-1])
        assert out["backend"] == backend
        depth, inst = np.array(out["depth"]), np.array(out["instance"])
        np.testing.assert_allclose(depth[inst == 0], 10.0, atol=2e-3)  # exact on each backend
        car = inst == 1
        assert car.sum() > 100
        # The car's visible surface lies in front of the wall and behind the camera's near range.
        assert np.all((depth[car] > 3.5) & (depth[car] < 10.0))
        results[backend] = (depth, inst)
    if len(results) == 2:
        (d1, i1), (d2, i2) = results.values()
        assert (i1 != i2).mean() < 0.002  # same rasterisation up to a few edge pixels
        same = i1 == i2
        np.testing.assert_allclose(d1[same], d2[same], rtol=1e-3)
