"""Suite-wide ordering."""

_PLAYWRIGHT_FIXTURES = {"page", "browser", "context", "playwright", "browser_type"}


def pytest_collection_modifyitems(session, config, items):
    # pytest-playwright keeps a session-wide event loop running in the main thread from
    # its first test on; Bokeh's Python client (tests/reliability) needs to run its own
    # loop there. Run every Playwright test after all others (stable order otherwise).
    items.sort(key=lambda item: bool(_PLAYWRIGHT_FIXTURES & set(item.fixturenames)))
