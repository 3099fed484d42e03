"""Built-in robot descriptions (TOML), and reading one by name or from a file."""

from __future__ import annotations

import tomllib
from importlib import resources
from pathlib import Path

from footfall.errors import ConfigError


def read_description(name_or_path: str | Path, builtin: tuple[str, ...]) -> dict:
    """The parsed TOML of a built-in robot (one of ``builtin``) or of a TOML file.

    Raises:
        ConfigError: When the name is unknown and no such file exists, or the file is not
            UTF-8 text or not TOML.
    """
    if str(name_or_path) in builtin:
        text = resources.files("footfall.robots").joinpath(f"{name_or_path}.toml").read_text()
    else:
        path = Path(name_or_path)
        if not path.is_file():
            raise ConfigError(
                f"robot {str(name_or_path)!r} is neither a built-in robot "
                f"({', '.join(builtin)}) nor an existing TOML file"
            )
        try:
            text = path.read_text(encoding="utf-8")
        except UnicodeDecodeError as exc:
            raise ConfigError(f"robot description {path} is not UTF-8 text: {exc}") from exc
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"robot description {name_or_path}: {exc}") from exc
