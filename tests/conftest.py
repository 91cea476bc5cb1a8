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
