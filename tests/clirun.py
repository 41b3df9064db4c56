"""The CLI run in-process by the tests: ``fempipe.cli.main(argv)`` with captured output."""

from __future__ import annotations

import json

from fempipe.cli import main


def run_json(capsys, argv) -> dict:
    """The JSON a successful command prints (the test fails with stderr otherwise)."""
    code = main(argv)
    out = capsys.readouterr()
    assert code == 0, out.err
    return json.loads(out.out)
