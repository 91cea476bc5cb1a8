"""One colour and one marker per matcher, the same in every figure.

Colours come from three colour-blind-safe palettes (Okabe & Ito's eight, then Paul Tol's
"muted" nine and "light" nine) and each matcher also has its own marker, so no two built-in matchers look alike even in
grey. A matcher without an entry (a user's own) gets the first colour and marker no built-in
uses, in the order the figure meets it.
"""

from __future__ import annotations

from typing import NamedTuple

OKABE_ITO = ("#E69F00", "#56B4E9", "#009E73", "#F0E442", "#0072B2", "#D55E00", "#CC79A7", "#000000")
TOL_MUTED = ("#CC6677", "#332288", "#DDCC77", "#117733", "#88CCEE", "#882255", "#44AA99",
             "#999933", "#AA4499")  # fmt: skip
TOL_LIGHT = ("#77AADD", "#EE8866", "#EEDD88", "#FFAABB", "#99DDFF", "#44BB99", "#BBCC33",
             "#AAAA00", "#DDDDDD")  # fmt: skip
TOL_DARK = ("#222255", "#225555", "#225522", "#666633", "#663333", "#555555")
MARKERS: tuple = ("o", "s", "^", "v", "D", "P", "X", "*", "<", ">", "h", "p", "d", "H", "8",
           "1", "2", "3", "4", "+", "x", "|", "_", (5, 1, 0), (6, 2, 0), (7, 1, 0))  # fmt: skip


class Style(NamedTuple):
    color: str
    marker: str


# The paper's methods first, maximin in black (the method the paper proposes), then the rest.
BUILTIN: dict[str, Style] = {
    name: Style(color, marker)
    for name, color, marker in zip(
        ("maximin", "sm", "rrwm", "tm", "hgm", "bcagm", "rrwhm", "mos", "appearance",
         "consistency", "pose", "pose_refine", "pose_appearance", "maximin_pose", "none",
         "cbm", "cbm_pose", "freealign", "freealign_pose", "optimal_transport",
         "optimal_transport_pose", "learned", "learned_pose", "maximin_learned", "rrwm_learned",
         "v2x_reg"),
        (OKABE_ITO[7], OKABE_ITO[0], OKABE_ITO[1], OKABE_ITO[2], OKABE_ITO[3], OKABE_ITO[4],
         OKABE_ITO[5], OKABE_ITO[6], TOL_MUTED[0], TOL_MUTED[1], TOL_MUTED[2], TOL_MUTED[3],
         TOL_MUTED[4], TOL_MUTED[5], "#BBBBBB", *TOL_LIGHT[:6], TOL_MUTED[6], TOL_MUTED[7],
         TOL_LIGHT[6], TOL_MUTED[8], TOL_LIGHT[7]),
        MARKERS[:26],
        strict=True,
    )
}  # fmt: skip


def styles(matchers: list[str]) -> dict[str, Style]:
    """The style of each of `matchers`: built-ins their own, others the unused ones in order."""
    used = {s.color for s in BUILTIN.values()}
    spare_colors = [
        c for c in (*TOL_MUTED, *TOL_LIGHT, *OKABE_ITO, *TOL_DARK) if c not in used
    ] or list(TOL_MUTED)
    out, k = {}, 0
    for name in matchers:
        if name in BUILTIN:
            out[name] = BUILTIN[name]
        else:
            out[name] = Style(spare_colors[k % len(spare_colors)], MARKERS[k % len(MARKERS)])
            k += 1
    return out
