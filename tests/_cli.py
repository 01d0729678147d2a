"""Helpers shared by the CLI tests (imported as ``from _cli import ...``)."""

from __future__ import annotations


def assert_one_line_error(result, *fragments: str) -> None:
    """A ``CliRunner`` result failed with exactly one ``error: ...`` line and no traceback,
    and that line names every fragment (file, channel, option)."""
    assert result.exit_code != 0
    assert result.exception is None or isinstance(result.exception, SystemExit)
    text = result.output  # stdout and stderr together
    assert "Traceback" not in text
    lines = [ln for ln in text.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error:"), text
    flat = " ".join(text.split())
    for f in fragments:
        assert f in flat, text
