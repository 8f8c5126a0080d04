"""Suite-wide ordering and Hypothesis's default profile."""
import os

from hypothesis import settings

# Derandomized unless HYPOTHESIS_PROFILE says otherwise: every run tries the same
# examples, so a CI verdict belongs to the code, not to the draw ("explore" draws anew).
settings.register_profile("ci", derandomize=True)
settings.register_profile("explore", derandomize=False)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))

_PLAYWRIGHT_FIXTURES = {"page", "browser", "context", "playwright", "browser_type"}


def pytest_collection_modifyitems(session, config, items):
    # pytest-playwright keeps a session-wide event loop running in the main thread from
    # its first test on; Bokeh's Python client (tests/reliability) needs to run its own
    # loop there. Run every Playwright test after all others (stable order otherwise).
    items.sort(key=lambda item: bool(_PLAYWRIGHT_FIXTURES & set(item.fixturenames)))
