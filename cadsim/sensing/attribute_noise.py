"""Attributes as a detector sees them: the class and 3-D size a view's detector reports for each
object, with seeded class confusion and size noise, so that the attribute part of the appearance
features gives no oracle advantage.

Per view, independently: each object is reported as another class of its *confusion group* with
probability ``class_confusion`` (uniformly among the group's other members: a detector mistakes a
van for a truck, a cyclist for a pedestrian, a sign for a traffic light — never a bus for a
pedestrian); classes outside every group are never confused. Each of its size's three dimensions
is multiplied by exp(``size_noise`` · ε), ε ~ N(0, 1) (log-normal, so a size stays positive and
``size_noise`` is about the relative error). Two views then disagree on a covisible object's class
with probability ≈ 2 · ``class_confusion``. Imports only numpy and ``cadsim.world``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from cadsim import portable_math as pm
from cadsim.world import WorldObject

CONFUSION_GROUPS: tuple[tuple[str, ...], ...] = (
    ("car", "van", "bus", "truck"),
    ("bicycle", "person"),
    ("traffic_light", "sign"),
    ("robot", "box", "cone"),
)


def perceived_attributes(
    objects: Sequence[WorldObject],
    class_confusion: float,
    size_noise: float,
    rng: np.random.Generator,
) -> tuple[list[str], np.ndarray]:
    """The class and size (metres, (n, 3): length, width, height) one view's detector reports for
    each of ``objects`` (a snapshot's whole list, so an object's attributes do not depend on
    which others are detected). Draws from ``rng`` in a fixed order: n uniforms (confused?), n
    uniforms (into which class), n × 3 normals (size), whatever the rates.

    >>> from cadsim.world import WorldObject
    >>> car = WorldObject("c", "car", "car", (0, 0, 0.75), 0.0, (4.6, 1.8, 1.5), (1, 1, 1))
    >>> cls, size = perceived_attributes([car], 1.0, 0.0, np.random.default_rng(0))
    >>> cls[0] in ("van", "bus", "truck"), size.tolist()
    (True, [[4.6, 1.8, 1.5]])
    """
    n = len(objects)
    confused = rng.random(n) < class_confusion
    choice = rng.random(n)
    eps = rng.standard_normal((n, 3))
    names = np.array([o.cls for o in objects], dtype=object)
    reported = names.copy()
    for group in CONFUSION_GROUPS:
        members = np.array(group, dtype=object)
        own = np.flatnonzero(confused & np.isin(names, members))
        if not own.size:
            continue
        k = np.argmax(names[own][:, None] == members[None, :], axis=1)  # index in the group
        step = 1 + np.floor(choice[own] * (len(group) - 1)).astype(int)
        reported[own] = members[(k + step) % len(group)]
    sizes = np.array([o.size for o in objects], dtype=float).reshape(n, 3)
    return [str(c) for c in reported], sizes * pm.exp(size_noise * eps)


__all__ = ["CONFUSION_GROUPS", "perceived_attributes"]
