from dataclasses import dataclass

import pytest

from surveil.config import from_table, read_toml, setting
from surveil.errors import ConfigError


@dataclass(frozen=True, kw_only=True)
class Inner:
    n: int = setting(100, "particles", min=50)
    mode: str = setting("a", "mode", choices=("a", "b"))


@dataclass(frozen=True, kw_only=True)
class Outer:
    name: str = setting(doc="required name")
    size: tuple[float, float] = setting((1.0, 2.0), "two numbers")
    colour: str | tuple[int, int, int] = setting("red", "name or rgb")
    inner: Inner = setting(default_factory=Inner)
    items: tuple[Inner, ...] = setting((), "a list of tables")
    limit: float | None = setting(None, "optional")


def test_nested_tables_and_lists_become_dataclasses():
    cfg = from_table(
        Outer,
        {
            "name": "x",
            "inner": {"n": 60},
            "items": [{"mode": "b"}],
            "size": [3, 4],
            "colour": [1, 2, 3],
        },
        "f.toml: ",
    )
    assert cfg.inner.n == 60 and cfg.items[0].mode == "b"
    assert cfg.size == (3.0, 4.0) and cfg.colour == (1, 2, 3) and cfg.limit is None


@pytest.mark.parametrize(
    ("table", "message"),
    [
        ({"name": "x", "inner": {"n": 3}}, r"f\.toml: inner\.n must be >= 50, got 3"),
        ({"name": "x", "inner": {"mode": "c"}}, r"inner\.mode must be one of 'a', 'b', got 'c'"),
        ({"name": "x", "bogus": 1}, r"f\.toml: bogus is not a known key; valid keys: colour"),
        ({}, r"f\.toml: name is required \(required name\)"),
        ({"name": "x", "size": [1]}, r"size must be a list of 2 values"),
        ({"name": "x", "items": [{"n": "many"}]}, r"items\[0\]\.n must be an integer"),
        ({"name": "x", "limit": True}, r"limit must be a number, got True"),
    ],
)
def test_errors_name_the_file_and_dotted_key(table, message):
    with pytest.raises(ConfigError, match=message):
        from_table(Outer, table, "f.toml: ")


def test_read_toml_reports_syntax_errors_with_the_file(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("a = [1,\n")
    with pytest.raises(ConfigError, match=r"bad\.toml: invalid TOML"):
        read_toml(bad)
    with pytest.raises(ConfigError, match="file not found"):
        read_toml(tmp_path / "missing.toml")
