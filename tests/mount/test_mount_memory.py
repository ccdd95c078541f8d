"""A device's records survive a restart, are kept apart per device, and a damaged record is one
clear error that leaves the file as it was."""

from __future__ import annotations

from pathlib import Path

import pytest

from scopelink.mount.memory import DeviceMemory, RecordError


def test_a_record_survives_a_new_memory_object_and_devices_are_kept_apart(tmp_path: Path) -> None:
    DeviceMemory("synscan-EQ6-/dev/ttyUSB0", tmp_path).save("park", {"axes": [1.5, 2.5]})
    assert DeviceMemory("synscan-EQ6-/dev/ttyUSB0", tmp_path).load("park") == {"axes": [1.5, 2.5]}
    assert DeviceMemory("synscan-EQ6-/dev/ttyUSB1", tmp_path).load("park") is None
    # The key never escapes the state directory, whatever the port's name.
    memory = DeviceMemory("../../etc/passwd", tmp_path)
    memory.save("park", {})
    assert memory.directory.resolve().is_relative_to(tmp_path.resolve())


def test_forget_removes_the_record(tmp_path: Path) -> None:
    memory = DeviceMemory("sim", tmp_path)
    memory.save("pointing", {"syncs": []})
    memory.forget("pointing")
    memory.forget("pointing")  # twice is fine
    assert memory.load("pointing") is None


def test_a_damaged_record_is_a_clear_error_and_is_left_alone(tmp_path: Path) -> None:
    memory = DeviceMemory("sim", tmp_path)
    memory.save("park", {"axes": [1.0, 2.0]})
    memory.path("park").write_text("{not json", encoding="utf-8")
    with pytest.raises(RecordError, match=r"park\.json is not readable JSON"):
        memory.load("park")
    assert memory.path("park").read_text(encoding="utf-8") == "{not json"
    memory.path("park").write_text("[1, 2]", encoding="utf-8")
    with pytest.raises(RecordError, match="does not hold a record"):
        memory.load("park")
