"""A drive file's one-line refusal, for the tests of its limits (geometry, ratio, modulus)."""

from __future__ import annotations

import pytest

from hdsim.errors import InputError
from hdsim.model.catalog import load_unit

#: the docs' example drive (docs/cli.md), without its optional figures
HEAD = 'name = "ZXF17-50"\nratio = 50\nrated_torque_Nm = 16.0\n'


def refusal(tmp_path, text: str) -> str:
    """The one-line refusal of a drive file holding ``text``; it names the file."""
    path = tmp_path / "drive.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(InputError) as info:
        load_unit(path)
    message = str(info.value)
    assert "\n" not in message and message.startswith(str(path)), message
    return message
