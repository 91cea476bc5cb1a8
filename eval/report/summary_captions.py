"""The README's compact tables: (lead, table builder, heading of the report section it links
to, caption) — each builder a function of :mod:`eval.report.summary` taking the results folder
and its claims."""

from __future__ import annotations

from eval.core.abstention import NO_NUMBER
from eval.report import levels_part, summary

# The README's compact tables: (lead, table, heading of the report section it links to, caption).
SUMMARIES = (
    (
        "Table I — where the methods differ: the headline difficulty level",
        levels_part.table1,
        "Difficulty levels",
        "F1 in percent on the test pairs of the difficulty level chosen on validation (the level "
        "where the paper's eight methods differ most there), under equal cues; the share of those "
        "pairs on which the top method is perfect, whether it is separated from the runner-up, "
        "and maximin against its best rival with the minimum detectable difference at 80 % power "
        "and the test clusters an MDD of 5 points would need. Intervals resample episodes.",
    ),
    (
        "Table I — the paper's benchmark, equal cues",
        summary.table1,
        "Table I",
        "F1 in percent on each dataset's test pairs, every one of the paper's eight methods "
        "handed the same cues — metric geometry and appearance, each in its family's natural "
        "form ([equal cues](docs/matchers.md#equal-cues)) — τ and parameters chosen on validation "
        "seeds; maximin's rank by test F1 among the eight with its 95 % interval (test episodes "
        "resampled), the paper's own rank of maximin (by accuracy) in brackets; the rival and "
        "the best of all chosen by validation F1, shown with their test F1; the difference's "
        "interval resamples simulation episodes. Each comparative cell is a row of "
        "`results/claims.csv`. The table with each method's published cues is in the report.",
    ),
    (
        "Fig. 4 — depth noise",
        summary.noise,
        "Fig. 4",
        "F1 in percent from the lowest to the highest noise rate (σ = rate · d²).",
    ),
    (
        "External data — the DMGM CAD pairs",
        summary.external,
        "External data",
        "Independently simulated (CARLA + SUMO), not real-world; τ and parameters from sequence "
        "070, test on 069 + 071, sorted as the full table; *prior*: given the vehicles' noisy "
        "GPS poses.",
    ),
    (
        "V2X — CAD-V2X under each localisation preset",
        summary.v2x,
        "The V2X task",
        "F1 in percent of the paper's method, two matchers without and two with the "
        "localisation prior (last column: the same data as 3-D boxes only, its matcher chosen on "
        f"validation; {NO_NUMBER}: no prior under `denied`, so no number); every matcher, the "
        "pose metrics and the verdicts in the report.",
    ),
    (
        "Multi-agent — fusing the pairwise matchings of N views",
        summary.multiagent,
        "Multi-agent",
        "Pooled pairwise F1 in percent per two-view matcher and fusion (`independent`: no fusion).",
    ),
    (
        "Temporal — association over sequences of 10 frames",
        summary.temporal,
        "The temporal table",
        "Pooled F1 in percent on CAD-V2X sequences (most frames of a sequence have no true pair, "
        "so the per-frame mean is secondary, in the report), one frame (W = 1) against a "
        f"10-frame window along each agent's own tracks (`trajectory_pose`: the window's motion "
        f"from the tracks alone, no prior); {NO_NUMBER}: the method reads the localisation "
        "prior, which `denied` does not give; the LiDAR sequences, the goals and their verdicts "
        "in the report.",
    ),
)
