"""What counts as a user's mistake rather than a bug, and how the command line reports one.

A user error is bad input: a scenario file, a dataset folder, a command-line value, a path. It is
a ``ValueError`` (``ScenarioError`` and ``DatasetError`` are), an ``OSError`` (missing file,
permission, disk full), or an exception that says so with a true ``user_error`` attribute
(``GenerationError``; ``matchers.PluginError``, a plug-in matcher or fusion that broke its
contract; ``eval.core.runner.RunFailed`` when every failed task failed on bad input). The
CLI reports it as one line, exit status 2; anything else is a bug and keeps its traceback.
"""

from __future__ import annotations


def is_user_error(exc: BaseException) -> bool:
    """Whether ``exc`` comes from bad input (see the module docstring)."""
    flagged = getattr(exc, "user_error", None)
    if flagged is not None:
        return bool(flagged)
    return isinstance(exc, ValueError | OSError)


MAX_MESSAGE = 1000  # characters of an error line; a message quoting a huge value is cut


def one_line(exc: BaseException) -> str:
    """The message of ``exc`` on one line (further lines joined with " | "), never empty, at most
    :data:`MAX_MESSAGE` characters (the middle of a longer one is cut, saying how much)."""
    lines = [line.strip() for line in str(exc).splitlines() if line.strip()]
    text = " | ".join(lines) or type(exc).__name__
    if len(text) > MAX_MESSAGE:
        cut = len(text) - MAX_MESSAGE
        text = (
            f"{text[: MAX_MESSAGE // 2]} … [{cut:,} characters cut] … {text[-MAX_MESSAGE // 2 :]}"
        )
    return text
