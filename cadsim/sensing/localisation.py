"""Localisation error (the scenario's ``[localisation]`` table): each observer's world pose as its
own GPS-like localisation reports it, and the object positions that noisy pose puts in the world.

An observer's pose error is a ground-plane translation (dx, dy) ~ N(0, position_sigma_m²) per axis
and a heading error dψ ~ N(0, yaw_sigma_deg²), drawn once per view and applied to the observer's
body pose (origin c: the carrying vehicle's centre; the camera is rigid on it). An object seen at
world position w (through the true pose) is reported at

    w' = R_z(dψ) (w − c) + c + (dx, dy, 0),

so the error of a whole view is one rigid ground-plane transform, as with a real pose estimate;
height is not perturbed. The standard-normal draws are scaled by the sigmas, so for one seed a
sweep over sigma scales the same error (common random numbers), and sigma 0 gives the true pose.

:meth:`LocalisationConfig.draw_error` draws it (a :class:`~cadsim.sensing.pose_error.PoseError`,
which :func:`~cadsim.sensing.pose_error.perturbed_world` applies). Imports numpy only; the reader (``cadsim.dataset.reader``) seeds and applies it at read time, so a
sweep over localisation error never re-renders.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from cadsim.config_tables import check_number, config_from_table
from cadsim.limits import MAX_PRIOR_SIGMA_M
from cadsim.sensing.gnss_error import model_of, parse_spec
from cadsim.sensing.pose_error import PoseError

MIN_STATED_SIGMA_M = 0.5
"""Floor of the prior's stated uncertainty (``Problem.world_sigma``), metres. With an exact pose
the prior still carries each detection's own position error (depth, box centre): on CAD, matched
objects placed through exact poses differ by 0.34 m median, 1.2 m at the 90th percentile, and a
matcher told "0 m" would gate every true pair out."""


@dataclass(frozen=True)
class LocalisationConfig:
    """The ``[localisation]`` table of a scenario file.

    position_sigma_m: standard deviation of an observer's position error per ground-plane axis,
    metres (DMGM's CAD data: 1.2). yaw_sigma_deg: standard deviation of its heading error, degrees
    (DMGM: 0.2). Both 0: exact poses (the prior is still given, error-free). preset: a
    GNSS-like error model of :mod:`cadsim.sensing.gnss_error` (``exact``, ``rtk``,
    ``gnss-open-sky``, ``gnss-urban``, ``denied``, optionally scaled or with another latency:
    a preset spec such as ``gnss-urban*2+300ms``) used instead of the two sigmas; None (the
    default): the i.i.d. model above, with no latency.
    """

    position_sigma_m: float = 1.2
    yaw_sigma_deg: float = 0.2
    preset: str | None = None

    def __post_init__(self) -> None:
        check_number(
            "[localisation]", "position_sigma_m", self.position_sigma_m,
            minimum=0.0, maximum=MAX_PRIOR_SIGMA_M,
        )  # fmt: skip
        check_number("[localisation]", "yaw_sigma_deg", self.yaw_sigma_deg, minimum=0.0)
        if self.preset is not None:
            try:
                parse_spec(self.preset)
            except ValueError as exc:
                raise ValueError(f"[localisation] {exc}") from None

    @classmethod
    def from_table(cls, table: Mapping, where: str = "[localisation]") -> LocalisationConfig:
        """Build from a scenario-file table; unknown keys/bad values raise naming ``where``."""
        return config_from_table(cls, table, where, "[localisation]")

    @property
    def stated_sigma_m(self) -> float:
        """The uncertainty a matcher is told (``Problem.world_sigma``): position_sigma_m — with
        a preset, the uncertainty its receiver reports — at least :data:`MIN_STATED_SIGMA_M`."""
        stated = float(self.position_sigma_m)
        if self.preset is not None:
            stated = model_of(self.preset).stated_sigma_m
        return max(stated, MIN_STATED_SIGMA_M)

    @property
    def latency_s(self) -> float:
        """Age of the other vehicle's message, seconds (the preset's; 0 without a preset)."""
        return 0.0 if self.preset is None else model_of(self.preset).latency_ms / 1000.0

    def draw_error(self, rng: np.random.Generator) -> PoseError:
        """One view's pose error under the i.i.d. model (module docstring): three standard
        normals from ``rng`` (always three, whatever the sigmas), scaled by the sigmas."""
        z = rng.standard_normal(3)
        s = float(self.position_sigma_m)
        return PoseError(s * z[0], s * z[1], np.radians(float(self.yaw_sigma_deg)) * z[2])

    def as_record(self) -> dict:
        """The ``prior`` fields a record stores (``preset`` only when one is set, so records of
        scenarios without one stay byte-identical)."""
        out = {"position_sigma_m": self.position_sigma_m, "yaw_sigma_deg": self.yaw_sigma_deg}
        return out if self.preset is None else out | {"preset": self.preset}
