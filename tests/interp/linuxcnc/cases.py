"""LinuxCNC's remap tests and sample configurations as cases to run (see README.md)."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import tarfile
from dataclasses import dataclass
from io import BytesIO
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[2]
EXPECTED = HERE / "expected"
# LinuxCNC's source: a bare git mirror; its tests are taken from the 2.9 branch
MIRROR = Path(os.environ.get("LINUXCNC_MIRROR", "/work/.mirror/LinuxCNC+linuxcnc/repo"))
MIRROR_REF = "2.9"
# Debian's linuxcnc-uspace installs the sample configurations here
EXAMPLES = Path("/usr/share/doc/linuxcnc/examples")
OUR_STDGLUE = REPO / "task" / "interp" / "python" / "glue"
# a sample's TOPLEVEL prints its process id: the same in every recording
_PID = re.compile(r"(interp __(?:init|delete)__ \d+) \d+")


@dataclass
class Case:
    name: str
    folder: str
    is_stdout_only: bool
    args: list[str]

    def recorded(self, suffix: str) -> Path:
        """The file of the recording (``.out``, ``.err``, ``.rc``; ``.ours.out`` ...)."""
        return EXPECTED / (self.name.replace("/", "__") + suffix)

    def prepare(self, scratch: Path) -> Path | None:
        """Copy the case's files under ``scratch``; the folder to run in, or None when
        they are not on this machine (no mirror, no sample configurations)."""
        if self.folder.startswith("tests/"):
            if not MIRROR.is_dir():
                return None
            archive = subprocess.run(
                ["git", f"--git-dir={MIRROR}", "archive", MIRROR_REF, self.folder],
                capture_output=True,
                check=False,
            )
            if archive.returncode != 0:
                return None
            with tarfile.open(fileobj=BytesIO(archive.stdout)) as tar:
                tar.extractall(scratch, filter="data")
            return scratch / self.folder
        if self.folder.startswith("configs/"):  # our own examples (their stdglue: see env)
            shutil.copytree(REPO / self.folder, scratch / self.folder)
            return scratch / self.folder
        source = EXAMPLES / "sample-configs" / self.folder
        remap_lib = EXAMPLES / "nc_files" / "remap_lib"
        if not source.is_dir() or not remap_lib.is_dir():
            return None
        shutil.copytree(source, scratch / self.folder)
        shutil.copytree(remap_lib, scratch / "nc_files" / "remap_lib")
        # the configurations name ../../nc_files: sim/axis/nc_files is a link, as installed
        (scratch / "sim" / "axis" / "nc_files").symlink_to("../../nc_files")
        return scratch / self.folder

    def linuxcnc_env(self) -> dict[str, str]:
        """More environment for LinuxCNC's rs274: our examples import stdglue, which ours
        has built in; LinuxCNC gets the same one (ours runs there unchanged), so that the
        recording tests the examples, our interpreter and our stdglue together."""
        if self.folder.startswith("configs/"):
            return {"PYTHONPATH": str(OUR_STDGLUE)}
        return {}

    def normalize(self, text: str, folder: Path) -> str:
        """Outputs without what differs from run to run: the scratch folder, process ids."""
        return _PID.sub(r"\1 PID", text.replace(str(folder), "SCRATCH"))


def cases() -> list[Case]:
    found = []
    for line in (HERE / "cases.txt").read_text().splitlines():
        if not line.strip() or line.startswith("#"):
            continue
        name, folder, compare, *args = line.split()
        found.append(Case(name, folder, compare == "stdout", args))
    return found
