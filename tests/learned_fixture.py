"""A model file for the learned matchers, trained once per test process on synthetic problems
(:func:`synthetic_pairs`), and the options a registry-wide test passes to a matcher that needs
one (:func:`needed_options`)."""

from __future__ import annotations

import tempfile
from functools import cache
from pathlib import Path

import numpy as np

from matchers import Problem, required_options


def synthetic_pair(rng: np.random.Generator, covisible: int = 8, extra: int = 3):
    """(Problem, truth): a 3-D scene seen by two cameras — ``covisible`` shared objects and
    ``extra`` of each view's own, view 2 rotated about z and shifted, 0.1 m position noise;
    appearance = the object's colour class plus noise; classes; a world prior (sigma 1 m)."""
    total = covisible + 2 * extra
    scene = rng.uniform(-25.0, 25.0, (total, 3)) * [1.0, 1.0, 0.1]
    colour = rng.integers(0, 4, total)
    look = np.eye(4)[colour] + rng.normal(0.0, 0.3, (total, 4)).clip(-0.5, 0.5)
    classes = np.array(["car", "van", "bus", "person"])[colour]
    in1 = np.r_[np.arange(covisible), covisible + np.arange(extra)]
    in2 = np.r_[np.arange(covisible), covisible + extra + np.arange(extra)]
    in2 = rng.permutation(in2)
    yaw = rng.uniform(0, 2 * np.pi)
    rot = np.array([[np.cos(yaw), -np.sin(yaw), 0], [np.sin(yaw), np.cos(yaw), 0], [0, 0, 1]])
    shift = rng.uniform(-10, 10, 3) * [1, 1, 0]
    p1 = scene[in1] + rng.normal(0, 0.1, (len(in1), 3))
    p2 = (scene[in2] - shift) @ rot + rng.normal(0, 0.1, (len(in2), 3))
    offset1, offset2 = rng.normal(0, 1.0, 3) * [1, 1, 0], rng.normal(0, 1.0, 3) * [1, 1, 0]
    problem = Problem(
        p1,
        p2,
        look[in1],
        look[in2],
        world1=scene[in1] + offset1,
        world2=scene[in2] + offset2,
        world_sigma=1.0,
        classes1=tuple(classes[in1]),
        classes2=tuple(classes[in2]),
    )
    where2 = {int(o): j for j, o in enumerate(in2)}
    truth = np.array([[i, where2[int(o)]] for i, o in enumerate(in1) if int(o) in where2])
    return problem, truth


def synthetic_pairs(seed: int, count: int):
    rng = np.random.default_rng(seed)
    return [synthetic_pair(rng) for _ in range(count)]


@cache
def model_path() -> str:
    """A model (both variants) trained on 30 synthetic problems, in a temporary folder."""
    from cadsim.commands.train import save_model
    from matchers.learned.training import train_model

    model = train_model(synthetic_pairs(0, 30), {"datasets": []}, rounds=40)
    path = Path(tempfile.mkdtemp(prefix="cadsim-model-")) / "synthetic.json"
    save_model(model, path)
    return str(path)


def needed_options(name: str) -> dict:
    """``{"model": path}`` for a matcher that needs a model file, else ``{}``."""
    return {"model": model_path()} if "model" in required_options(name) else {}
