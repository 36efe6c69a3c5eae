"""Finding the controller: the runtime-info file, an NML or INI argument, cnc.nmlfile."""

from __future__ import annotations

import json
import os
from collections.abc import Iterator
from pathlib import Path

import pytest

import cnc
from cnc.runtime import (
    read_runtime_info,
    remove_runtime_info,
    runtime_info_path,
    write_runtime_info,
)
from nml import emc
from nml.channels import DEFAULT_NML_FILE, EMC_COMMAND, EMC_ERROR, EMC_STATUS, Nml, load_config
from tests.conftest import Processes


def test_runtime_info_is_written_read_and_removed(runtime_dir: Path, cnc_instance: str) -> None:
    path = write_runtime_info("mill.ini", DEFAULT_NML_FILE)
    assert path == runtime_dir / f"cnc-{cnc_instance}.json" == runtime_info_path()
    record = json.loads(path.read_text())
    assert record["pid"] == os.getpid() and record["instance"] == cnc_instance
    info = read_runtime_info()
    assert info is not None
    assert (info.ini, info.nml) == (Path("mill.ini").resolve(), DEFAULT_NML_FILE)
    remove_runtime_info()
    assert not path.exists() and read_runtime_info() is None


def test_a_file_left_by_a_dead_launcher_is_ignored(procs: Processes) -> None:
    dead = procs.python("-c", "pass")
    dead.wait()
    path = runtime_info_path()
    path.write_text(
        json.dumps({"instance": "x", "ini": "/a.ini", "nml": "/a.nml", "pid": dead.pid})
    )
    assert read_runtime_info() is None
    remove_runtime_info()
    assert not path.exists()


@pytest.fixture
def other_nml(tmp_path: Path) -> Iterator[Path]:
    """A running machine whose NML file differs from ours (a larger emcStatus), so that
    attaching with the default file would fail."""
    text = DEFAULT_NML_FILE.read_text().replace(
        "B emcStatus     SHMEM  localhost  32768", "B emcStatus     SHMEM  localhost  40960"
    )
    path = tmp_path / "machine" / "other.nml"
    path.parent.mkdir()
    path.write_text(text)
    with Nml(load_config(path), "cnc", [EMC_COMMAND, EMC_STATUS, EMC_ERROR]) as nml:
        nml[EMC_STATUS].write(emc.EMC_STAT(echo_serial_number=77))
        yield path


def polled_serial(s: cnc.stat) -> int:
    s.poll()
    return s.echo_serial_number


def test_no_argument_finds_the_running_machine(other_nml: Path) -> None:
    with pytest.raises(cnc.error, match="expected"):
        cnc.stat().poll()  # no runtime info: the default NML file does not fit
    write_runtime_info(other_nml.with_name("mill.ini"), other_nml)
    try:
        assert cnc.nmlfile == str(other_nml)
        assert polled_serial(cnc.stat()) == 77
    finally:
        remove_runtime_info()


def test_an_ini_file_names_the_nml_file_relative_to_its_folder(other_nml: Path) -> None:
    ini = other_nml.with_name("mill.ini")
    ini.write_text("[EMC]\nMACHINE = mill\nNML_FILE = other.nml\n")
    assert polled_serial(cnc.stat(ini)) == 77
    assert polled_serial(cnc.stat(str(other_nml))) == 77


def test_assigning_nmlfile_overrides_the_default(
    other_nml: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(cnc, "nmlfile", str(other_nml), raising=False)
    assert polled_serial(cnc.stat()) == 77


def test_a_missing_nml_file_is_a_cnc_error(tmp_path: Path) -> None:
    with pytest.raises(cnc.error, match="cannot read NML file"):
        cnc.stat(tmp_path / "nowhere.nml")
