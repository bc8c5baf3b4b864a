"""The bad-input suites report what they tried at the end of the run (issue: the fuzz suite
says how many (key, bad value) pairs and which subcommand x corrupt-file cases it tried)."""

import pytest

_LINES = pytest.StashKey[list]()


@pytest.fixture
def fuzz_report(request):
    """A list of lines printed in the terminal summary under 'bad input tried'."""
    return request.config.stash.setdefault(_LINES, [])


def pytest_terminal_summary(terminalreporter, config):
    lines = config.stash.get(_LINES, [])
    if lines:
        terminalreporter.section("bad input tried")
        for line in lines:
            terminalreporter.write_line(line)
