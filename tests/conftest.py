"""Fixtures shared across test modules."""

import pytest
from render_fixtures import H, W


@pytest.fixture(scope="module")
def renderer():
    """A W×H off-screen renderer per test module (the GL backend is chosen by the code)."""
    from cadsim.render import Renderer

    r = Renderer(W, H)
    yield r
    r.close()


# Hypothesis profiles: the default keeps `make test` quick; `--hypothesis-profile=long` fuzzes
# thousands of examples per property (tests/test_matchers_fuzz.py, the importer's fuzz test).
from hypothesis import settings  # noqa: E402

settings.register_profile("long", max_examples=2000, deadline=None)
