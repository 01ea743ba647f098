"""Bytes that are not a UTF-8 TOML scenario, as a user may pass by mistake (issue 14 §2),
shared by tests/scenario/test_bad_input.py and tests/test_cli_errors.py."""
from __future__ import annotations

import gzip


def not_utf8_files(text: str) -> dict:
    """``{kind: bytes}``: binary, PNG, gzip, UTF-16 and one latin-1 byte; ``text`` is a valid
    scenario containing ``"torque-free body"`` (the shipped paper-torque-free.toml)."""
    assert "torque-free body" in text
    return {
        "binary": bytes(range(256)),
        "png": b"\x89PNG\r\n\x1a\n" + bytes(64),
        "gzip": gzip.compress(text.encode()),
        "utf-16": text.encode("utf-16"),
        "latin-1 byte": text.replace("torque-free body", "torque-free b\xf6dy").encode("latin-1"),
    }
