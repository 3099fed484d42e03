"""Registries: names to entries, loaded lazily by path, with errors that list the choices."""

from __future__ import annotations

import sys

import pytest

from footfall.errors import ConfigError
from footfall.registry import Registry


def test_entries_keep_their_order_and_unknown_names_list_the_known():
    """Entries come back in registration order; asking for another name is an error that
    names it and lists what is registered, by `get` and by `check` alike."""
    things = Registry[int]("thing")
    things.register("one", 1)
    things.register("two", 2)
    assert things.names() == ("one", "two") and list(things) == ["one", "two"]
    assert things.get("two") == 2 and "one" in things and len(things) == 2
    for ask in (things.get, things.check):
        with pytest.raises(ConfigError, match=r"unknown thing 'three'; choose one of one, two"):
            ask("three")


def test_a_name_is_registered_once_and_may_be_withdrawn():
    """A second entry under a taken name is refused; an empty name too; unregistering frees
    the name."""
    things = Registry[int]("thing")
    things.register("one", 1)
    with pytest.raises(ConfigError, match="already registered"):
        things.register("one", 11)
    with pytest.raises(ConfigError, match="non-empty name"):
        things.register("", 0)
    things.unregister("one")
    things.register("one", 11)
    assert things.get("one") == 11


def test_the_decorator_form_registers_and_returns_the_class():
    """`@registry.register(name)` registers the class and leaves it as it was."""
    kinds = Registry[type]("kind")

    @kinds.register("plain")
    class Plain:
        pass

    assert kinds.get("plain") is Plain


def test_a_path_entry_is_imported_only_when_asked_for(tmp_path, monkeypatch):
    """A "module:attribute" entry does not import its module until chosen (a hardware
    library stays unloaded), then resolves to the object; a path that does not resolve is
    an error naming the entry."""
    (tmp_path / "footfall_test_driver.py").write_text("class Driver:\n    pass\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    kinds = Registry[object]("backend")
    kinds.register("driver", "footfall_test_driver:Driver")
    kinds.register("missing", "footfall_no_such_module:Driver")
    assert kinds.check("driver") == "driver" and "footfall_test_driver" not in sys.modules
    driver = kinds.get("driver")
    assert driver is sys.modules["footfall_test_driver"].Driver
    with pytest.raises(ConfigError, match="backend 'missing' cannot be loaded"):
        kinds.get("missing")
    monkeypatch.delitem(sys.modules, "footfall_test_driver")
