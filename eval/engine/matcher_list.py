"""Which matchers a ``--matchers`` list names (:func:`parse_matchers`): ``all`` or names,
checked against the registry, in the paper's order (:data:`PAPER_ORDER`); the matchers that read
the localisation prior (:func:`prior_matchers`) and a list with them (:func:`with_prior`). Every
command, stage and study that takes a matcher list parses it here."""

from __future__ import annotations

from eval.core.tasks import MatcherSpec

PAPER_ORDER = ("sm", "rrwm", "hgm", "tm", "bcagm", "rrwhm", "mos", "maximin", "appearance", "none")


def parse_matchers(text: str) -> list[MatcherSpec]:
    """``all`` or a comma-separated list of names, case-insensitive (``SM,Maximin`` as the tables
    print them). ``all``: every registered matcher that needs nothing beyond what every dataset
    gives (``matchers.requires`` empty; the localisation-prior matchers must be named) and needs
    no option (``matchers.required_options`` empty: the learned matchers need a model), paper
    order first; an entry point that cannot be loaded is left out with a warning line. An
    unknown name is refused with the closest known ones, a named entry point that cannot be
    loaded in one line naming it (``matchers.PluginError``)."""
    from matchers.core.registry import available, get, required_options, requires, usable

    known = list(available())
    if text.strip() == "all":
        plain = [n for n in usable() if not requires(n) and not required_options(n)]
        names = [n for n in PAPER_ORDER if n in plain] + [n for n in plain if n not in PAPER_ORDER]
    else:
        by_lower = {n.lower(): n for n in known}
        given = [n.strip() for n in text.split(",") if n.strip()]
        names = [n if n in known else by_lower.get(n.lower(), n) for n in given]
        unknown = [n for n in names if n not in known and not _importable(n)]
        if unknown or not names:
            import difflib

            close = difflib.get_close_matches(unknown[0].lower(), known, n=3) if unknown else []
            hint = f" (did you mean {', '.join(close)}?)" if close else ""
            raise ValueError(
                f"--matchers: unknown {unknown or text!r}{hint}; available: {', '.join(known)}"
            )
        for name in names:
            get(name)  # a broken entry point: PluginError naming it, before anything runs
    return [MatcherSpec(n) for n in dict.fromkeys(names)]


def _importable(name: str) -> bool:
    """Whether ``name`` is a ``package.module:function`` matcher that imports; one that does
    not raises ValueError saying why (its module, the ImportError, how to make it importable)."""
    if ":" not in name:
        return False
    from matchers.core.registry import get

    get(name)
    return True


def prior_matchers() -> list[str]:
    """Registered matchers that need the localisation prior (``matchers.requires`` names it) and
    no option (the learned matchers need a model: named with it); broken entry points are left
    out (``matchers.usable``)."""
    from matchers.core.registry import required_options, requires, usable

    return [n for n in usable() if "world1" in requires(n) and not required_options(n)]


def with_prior(text: str = "all") -> list[MatcherSpec]:
    """``all``: every matcher of ``cadsim evaluate --matchers all`` plus the prior matchers;
    otherwise the comma list as given (:func:`parse_matchers`)."""
    specs = parse_matchers(text)
    if text.strip() == "all":
        specs += [MatcherSpec(n) for n in prior_matchers()]
    return list(dict.fromkeys(specs))


__all__ = ["PAPER_ORDER", "parse_matchers", "prior_matchers", "with_prior"]
