"""Telling the operator about hardware faults, from drivers in any process.

``operator_channel(process)`` returns a function that puts a text on the machine's error
channel (``emcError``, what every UI shows), or None when no machine runs (a plain
``halrun``: the driver's stderr is all there is). It never waits: a full channel drops its
oldest message. ``process`` is the NML file's P line to write as: ``motion`` from the
realtime host (its timeout 0 never blocks a servo period), ``tool`` from userspace.
"""

from __future__ import annotations

import os
from collections.abc import Callable


def operator_channel(process: str) -> Callable[[str], None] | None:
    nml_file = os.environ.get("CNC_NML_FILE")
    if not nml_file:
        return None
    try:
        from nml import emc
        from nml.channels import EMC_ERROR, Nml, load_config

        nml = Nml(load_config(nml_file), process, [EMC_ERROR])
    except Exception:
        return None

    def tell(text: str) -> None:
        message = emc.EMC_OPERATOR_ERROR(error=emc.fit_text(text))
        nml[EMC_ERROR].write(message, is_oldest_dropped=True)

    return tell
