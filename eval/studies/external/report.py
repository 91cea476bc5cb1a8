"""The external study's report part: the table as written, and what it says — the best
matcher without and with the prior (chosen on the test pairs themselves: point values labelled
so), maximin given the prior against that best, DMGM's published figure — each comparison a
claim (:func:`claims`). Reads the written files; runs nothing."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from eval.protocol.claims import Claim, claims_in, lines_of, point_claim, printed
from eval.studies.external.evaluation import DMGM_PUBLISHED, SOURCE, SUBDIR


def findings(table: pd.DataFrame) -> list[str]:
    """The sentences of :func:`finding_items`, as the report prints them."""
    return lines_of(finding_items(table))


def finding_items(table: pd.DataFrame) -> list[Claim | str]:
    """What the external table says (pooled F1, percent), in order: the best matcher without
    the prior and the best with it — claims chosen on the test pairs themselves, so point values
    labelled so —, the prior alone, maximin given the prior against that best (a point value)
    and DMGM's published figure (plain lines)."""
    ours = table[table["source"] == "ours"]
    free = ours[~ours["uses_prior"].astype(bool) & (ours["matcher"] != "none")]
    prior = ours[ours["uses_prior"].astype(bool)]
    out: list[Claim | str] = []

    def best(rows: pd.DataFrame) -> pd.Series:
        return rows.loc[rows["f1_pooled_mean"].idxmax()]

    def leader(rows: pd.DataFrame, what: str, text: str) -> Claim:
        b = best(rows)
        return point_claim(
            SUBDIR, str(b["matcher"]), what, "pooled F1", printed(b["f1_pooled_mean"]),
            statement=text.format(method=b["method"], f1=f"{100 * b['f1_pooled_mean']:.1f}")
            + " (the highest test figure: a point value, chosen on test)",
            chosen_on="test", source=SOURCE,
        )  # fmt: skip

    if len(free):
        out.append(
            leader(
                free,
                "best without the prior, by test pooled F1",
                "without the prior (camera-frame geometry and appearance), the best matcher is "
                "{method} at pooled F1 {f1}",
            )
        )
    pose = prior[prior["matcher"] == "pose"]
    if len(pose):
        out.append(
            f"Hungarian on the noisy world positions alone (pose) reaches "
            f"{100 * pose['f1_pooled_mean'].iloc[0]:.1f}"
        )
    if len(prior):
        out.append(
            leader(
                prior,
                "best with the prior, by test pooled F1",
                "the best matcher with the prior is {method} at {f1}",
            )
        )
    maximin_pose = prior[prior["matcher"] == "maximin_pose"]
    if len(maximin_pose) and len(prior):
        top = best(prior)
        gap = top["f1_pooled_mean"] - maximin_pose["f1_pooled_mean"].iloc[0]
        if gap > 0:
            out.append(
                point_claim(
                    SUBDIR,
                    "maximin_pose",
                    str(top["matcher"]),
                    "pooled F1 points",
                    printed(-gap),
                    statement=f"maximin given the prior is {100 * gap:.1f} points below that "
                    "(no interval: a point value)",
                    chosen_on="test",
                    source=SOURCE,
                )  # fmt: skip
            )
    out.append(
        f"DMGM's published figure is {100 * DMGM_PUBLISHED['f1']:.1f} (threshold chosen on its "
        "test set, all 9,209 pairs)"
    )
    return out


def claims(results: Path) -> list[Claim]:
    """The external study's comparisons as claims (none without ``table_external.md``)."""
    results = Path(results)
    if not (results / "table_external.md").is_file():
        return []
    table = pd.read_csv(results / SOURCE, keep_default_na=False, na_values=[""])
    return claims_in(finding_items(table))


def readme_part(results: Path, rel: str) -> list[str]:
    """README lines for the external benchmark (none without ``table_external.md``)."""
    results = Path(results)
    path = results / "table_external.md"
    if not path.is_file():
        return []
    table = pd.read_csv(results / SOURCE, keep_default_na=False, na_values=[""])
    text = "; ".join(findings(table))
    return [
        "### External data: the DMGM CAD pairs",
        "",
        "310 frame pairs of the same research group's public CAD test data, shipped converted in "
        "`eval/data/dmgm-cad/` (MIT licence, provenance in its README): **independently simulated "
        "data (CARLA + SUMO), not real-world recordings**. τ and parameters from driving sequence "
        "070, test on 069 + 071; matchers marked *prior* get the vehicles' own noisy GPS poses "
        "(σ 1.2 m, 0.2°) that come with the data.",
        "",
        path.read_text().strip(),
        "",
        f"On these pairs: {text}. (`{rel}/table_external.csv`, "
        f"`{rel}/external/`: per-pair metrics, τ, tuning.)",
        "",
    ]
