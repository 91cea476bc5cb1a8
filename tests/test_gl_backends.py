"""One dataset on every GL backend: OSMesa and Mesa's EGL draw the same scenario and seed into
byte-identical datasets (each backend in its own process: PyOpenGL binds its platform once), the
manifest records the GL driver that drew, and ``cadsim info`` says when that was a vendor GPU's
EGL driver."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from cadsim.cli import main
from cadsim.render.backend import BACKENDS, _missing_libraries

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = ROOT / "scenarios" / "cad-intersection.toml"


def _generate(backend: str, out: Path, env_var: str = "CADSIM_GL_BACKEND") -> dict:
    """`cadsim generate` of one pair (seed 4242) in a fresh process on `backend`; its manifest."""
    env = {
        k: v for k, v in os.environ.items() if k not in ("CADSIM_GL_BACKEND", "PYOPENGL_PLATFORM")
    }
    env |= {env_var: backend, "SDL_VIDEODRIVER": "dummy", "MPLBACKEND": "Agg"}
    done = subprocess.run(
        [sys.executable, "-m", "cadsim", "generate", str(SCENARIO), "--pairs", "1",
         "--seed", "4242", "--workers", "1", "--no-progress", "--out", str(out)],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    return json.loads((out / "manifest.json").read_text())


def _record_bytes(root: Path) -> dict[str, bytes]:
    files = sorted(p for p in (root / "pairs").rglob("*") if p.is_file())
    return {str(p.relative_to(root)): p.read_bytes() for p in files}


MISSING = {name: _missing_libraries(spec) for name, spec in BACKENDS.items()}


@pytest.mark.skipif(
    any(MISSING.values()),
    reason=f"a GL backend's libraries are not installed ({MISSING}; `make` installs both)",
)
def test_osmesa_and_mesa_egl_give_byte_identical_datasets(tmp_path):
    osmesa = _generate("osmesa", tmp_path / "osmesa")
    egl = _generate("egl", tmp_path / "egl", env_var="PYOPENGL_PLATFORM")  # pyrender's advice
    assert egl["checksum"] == osmesa["checksum"]
    assert _record_bytes(tmp_path / "egl") == _record_bytes(tmp_path / "osmesa")
    assert [g["backend"] for g in osmesa["gl"]] == ["osmesa"]
    assert [g["backend"] for g in egl["gl"]] == ["egl"]
    for manifest in (osmesa, egl):
        (gl,) = manifest["gl"]
        assert gl["renderer"] and gl["vendor"] and gl["version"]
        assert gl["gpu_driver"] is not gl["renderer"].lower().startswith(("llvmpipe", "softpipe"))


def test_cadsim_info_names_the_driver_and_warns_for_a_vendor_gpu(tmp_path, capsys):
    if MISSING["osmesa"] and MISSING["egl"]:
        pytest.skip("no GL backend installed")
    backend = "osmesa" if not MISSING["osmesa"] else "egl"
    manifest = _generate(backend, tmp_path / "d")
    assert main(["info", str(tmp_path / "d")]) == 0
    out = capsys.readouterr().out
    assert f"rendered by             {backend}: " in out and "vendor GPU" not in out
    manifest["gl"] = [
        {"backend": "egl", "vendor": "NVIDIA Corporation", "renderer": "NVIDIA H100/PCIe/SSE2",
         "version": "4.6.0 NVIDIA 550.54", "gpu_driver": True}
    ]  # fmt: skip
    (tmp_path / "d" / "manifest.json").write_text(json.dumps(manifest))
    assert main(["info", str(tmp_path / "d")]) == 0
    out = capsys.readouterr().out
    assert "egl: NVIDIA H100/PCIe/SSE2 (NVIDIA Corporation" in out
    assert "drawn by a vendor GPU's EGL driver" in out
