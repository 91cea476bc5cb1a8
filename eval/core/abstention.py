"""Abstention is not a score (DESIGN §3): a method that cannot run under a condition — it
requires an input the condition does not give, the localisation prior under ``denied`` — gets
no number, never the value the per-frame conventions give a frame with nothing declared.

One rule, :func:`absent_inputs`: the optional problem fields a method declares in its
``requires`` attribute (``matchers.blocks.prior.PRIOR_FIELDS`` for every prior reader) less the
fields the condition gives. Two readings of "the condition": a localisation (a preset spec
such as ``denied`` or ``gnss-urban*2+300ms``, an error-scale pair, or None for the data's own
prior) — :func:`cannot_run` — and one problem's fields — :func:`problem_lacks`. Tables write
such a cell as NaN (an empty CSV cell) and print :data:`NO_NUMBER`; rankings, "best" and
comparisons leave the method out.
"""

from __future__ import annotations

from collections.abc import Iterable

NO_NUMBER = "n/a (needs a prior)"
"""What a Markdown cell says where a method could not run for want of the prior."""


def absent_inputs(requires: Iterable[str], given: Iterable[str]) -> frozenset[str]:
    """The fields of ``requires`` (what a method declares it needs) not in ``given`` (what the
    condition provides); empty when the method can run."""
    return frozenset(requires) - frozenset(given)


def given_fields(localisation: str | tuple | None) -> frozenset[str]:
    """The prior fields a localisation condition provides: all of them unless it is a preset
    spec whose model gives no pose (``denied``). None (the data's own prior) and an error-scale
    pair give the prior. ValueError naming the accepted forms for an unknown spec."""
    from matchers.blocks.prior import PRIOR_FIELDS

    if isinstance(localisation, str):
        from cadsim.sensing.gnss_error import model_of

        return PRIOR_FIELDS if model_of(localisation).given else frozenset()
    return PRIOR_FIELDS


def requirement(name: str, temporal: bool = False) -> frozenset[str]:
    """The ``requires`` attribute of matcher ``name`` — a registered name or a table's row label
    with its options, ``pose_refine[gate=4.0]`` (``temporal``: of the temporal matcher ``name``,
    e.g. ``temporal_pose`` or ``windowed:pose_refine``); empty for an unknown name."""
    name = name.partition("[")[0]
    try:
        if temporal:
            from matchers.core.temporal_registry import get_temporal

            return frozenset(getattr(get_temporal(name), "requires", ()))
        from matchers.core.registry import requires

        return requires(name)
    except ValueError:
        return frozenset()


def cannot_run(name: str, localisation: str | tuple | None, temporal: bool = False) -> bool:
    """Whether matcher ``name`` requires an input that ``localisation`` does not give (a prior
    reader under ``denied``): its cells get no number.

    >>> cannot_run("pose_refine", "denied"), cannot_run("pose_refine", "gnss-urban")
    (True, False)
    >>> cannot_run("maximin", "denied"), cannot_run("temporal_pose", "denied", temporal=True)
    (False, True)
    >>> cannot_run("pose[gate=4.0]", "denied")
    True
    """
    needs = requirement(name, temporal)
    return bool(needs) and bool(absent_inputs(needs, given_fields(localisation)))


def problem_lacks(requires: Iterable[str], problem: object) -> bool:
    """Whether ``problem`` lacks a field of ``requires`` (None there): the method cannot run on
    it."""
    given = [f for f in requires if getattr(problem, f, None) is not None]
    return bool(absent_inputs(requires, given))
