"""Tool changer bookkeeping: the prepare/change handshakes and the authoritative tool table.

Pure logic, no HAL and no NML, so every rule is testable in-process. ``IoControl`` copies the
attributes below to the ``iocontrol.0.*`` pins and to ``EMC_IO_STAT.tool`` every cycle.

Indices are LinuxCNC's *tooldata indices* (TOOL-011/012): index 0 is the spindle; with a
random changer the index is the pocket number, with a nonrandom one it is the load order and
the file's pocket number stays in ``ToolEntry.pocketno``.

Handshakes (IO-006, IO-007): ``prepare`` raises ``is_preparing`` (pin ``tool-prepare``) and
``start_change`` raises ``is_changing`` (pin ``tool-change``); ``poll`` takes the inputs
``tool-prepared`` / ``tool-changed`` and completes whichever handshake they acknowledge.
"""

from __future__ import annotations

from iocontrol.tooltable import CANON_POCKETS_MAX, ToolEntry, ToolTable

NO_POCKET = -1  # pocketPrepped when nothing is prepared (so that T0 can be prepared)


class ToolChangeError(Exception):
    """A tool command that cannot be carried out; the text is for the operator."""


def empty_spindle() -> ToolEntry:
    """The spindle record after a nonrandom changer unloads it (T0 M6)."""
    return ToolEntry(toolno=0, pocketno=0)


class ToolChanger:
    """Tool table, spindle and handshake state of one machine (TOOL-001..009, IO-006..015)."""

    def __init__(self, table: ToolTable) -> None:
        self.table = table
        self.is_random = table.random_toolchanger
        self.pocket_prepped = NO_POCKET  # an index, despite the name (TOOL-012)
        self.tool_from_pocket = 0
        # HAL outputs of the handshake (IO-009)
        self.prep_number = 0
        self.prep_pocket = 0
        self.prep_index = 0
        self.is_preparing = False
        self.is_changing = False
        if self.is_random:
            # the tool in pocket 0, as LinuxCNC: -1 when the table has none there
            self.tool_in_spindle = table.get(0).toolno
        else:
            # a nonrandom changer starts believing the spindle is empty (TOOL-003); its
            # record is the cleared one LinuxCNC's table load leaves (tool -1, pocket -1),
            # so that #<_current_pocket> reads -1 until the first tool change
            self.tool_in_spindle = 0
            table.put(0, ToolEntry())

    # ------------------------------------------------------------------ queries
    @property
    def is_pending(self) -> bool:
        """True while a handshake waits for tool-prepared or tool-changed (NML-042)."""
        return self.is_preparing or self.is_changing

    def spindle(self) -> ToolEntry:
        """The record of the tool in the spindle (``toolTable[0]``)."""
        return self.table.get(0)

    # ------------------------------------------------------------------ prepare (T)
    def prepare(self, toolno: int) -> None:
        """EMC_TOOL_PREPARE: set the prep pins and raise tool-prepare (IO-006).

        Preparing the tool that a random changer already holds in the spindle needs no
        handshake; nonrandom T0 ("no tool", TOOL-003) is prepared with number and pocket 0.
        """
        index = self.table.find_index_for_tool(toolno)
        if index < 0:
            self.pocket_prepped = NO_POCKET
            raise ToolChangeError(f"cannot prepare tool {toolno}: it is not in the tool table")
        entry = self.table.get(index)
        self.prep_index = index
        if index == 0:
            self.prep_number = entry.toolno if self.is_random else 0
            self.prep_pocket = 0
            self.pocket_prepped = 0
            if self.is_random:
                return
        else:
            self.prep_number = entry.toolno
            self.prep_pocket = entry.pocketno
        self.is_preparing = True

    # ------------------------------------------------------------------ change (M6)
    def start_change(self) -> None:
        """EMC_TOOL_LOAD: raise tool-change unless there is nothing to change (IO-007)."""
        if self.pocket_prepped == NO_POCKET:
            raise ToolChangeError("tool change requested, but no tool is prepared")
        if self.is_random and self.pocket_prepped == 0:
            return  # the prepared tool already is in the spindle
        prepared = self.table.get(self.pocket_prepped)
        if (
            not self.is_random
            and self.pocket_prepped > 0
            and prepared.toolno == self.tool_in_spindle
        ):
            return  # already loaded
        self.is_changing = True

    def poll(self, is_prepared: bool, is_changed: bool) -> bool:
        """Complete a handshake the changer acknowledged; True if one completed."""
        if self.is_preparing and is_prepared:
            self.pocket_prepped = self.prep_index
            self.is_preparing = False
            return True
        if self.is_changing and is_changed:
            self._finish_change()
            return True
        return False

    def _finish_change(self) -> None:
        index = self.pocket_prepped
        if not self.is_random and index == 0:
            self.tool_in_spindle = 0
            self.tool_from_pocket = 0
        else:
            loaded = self.table.get(index)
            self.tool_in_spindle = loaded.toolno
            self.tool_from_pocket = loaded.pocketno if loaded.toolno != 0 else 0
        self.load_tool(index)
        self.pocket_prepped = NO_POCKET
        self.prep_number = self.prep_pocket = self.prep_index = 0
        self.is_changing = False

    def load_tool(self, index: int) -> None:
        """Move the record at ``index`` into the spindle (IO-008, TOOL-002/004).

        Random: swap the spindle and the pocket, so the previous spindle tool takes the
        pocket. Nonrandom: copy the record to the spindle; index 0 empties the spindle.
        """
        if self.is_random:
            in_spindle, in_pocket = self.table.get(0), self.table.get(index)
            in_spindle.pocketno, in_pocket.pocketno = index, 0
            self.table.put(index, in_spindle)
            self.table.put(0, in_pocket)
        elif index == 0:
            self.table.put(0, empty_spindle())
        else:
            self.table.put(0, self.table.get(index))

    def cancel(self) -> None:
        """Drop tool-prepare and tool-change (EMC_TOOL_ABORT, e-stop; IO-013)."""
        self.is_preparing = False
        self.is_changing = False

    def reset_outputs(self) -> None:
        """All handshake outputs to their safe value (EMC_IO_INIT, e-stop)."""
        self.cancel()
        self.prep_number = self.prep_pocket = self.prep_index = 0
        self.tool_from_pocket = 0

    # ------------------------------------------------------------------ M61, unload
    def set_number(self, index: int) -> None:
        """EMC_TOOL_SET_NUMBER (M61): the record at ``index`` is now in the spindle, without
        a handshake (IO-012, TOOL-027). Like LinuxCNC 2.9, the command carries the index."""
        self._check_index(index)
        self.load_tool(index)
        self.tool_in_spindle = max(0, self.table.get(0).toolno)
        # as LinuxCNC's iocontrol: tool-from-pocket only changes to 0 for an empty spindle
        # (it keeps the pocket of the last handshake change otherwise)
        if self.tool_in_spindle == 0:
            self.tool_from_pocket = 0

    def unload(self) -> None:
        """EMC_TOOL_UNLOAD: the spindle is empty (IO-013)."""
        self.tool_in_spindle = 0
        self.tool_from_pocket = 0
        if not self.is_random:
            self.table.put(0, empty_spindle())

    # ------------------------------------------------------------------ table edits
    def set_offset(
        self,
        index: int,
        toolno: int,
        offset: list[float],
        diameter: float,
        frontangle: float,
        backangle: float,
        orientation: int,
    ) -> None:
        """EMC_TOOL_SET_OFFSET (G10 L1/L10/L11): update one record (IO-011).

        On a nonrandom changer the spindle copy of the same tool is updated too.
        """
        self._check_index(index)
        entry = self.table.get(index)
        entry.toolno = toolno
        entry.offset = list(offset)
        entry.diameter = diameter
        entry.frontangle = frontangle
        entry.backangle = backangle
        entry.orientation = orientation
        if entry.pocketno == -1:
            entry.pocketno = index  # a new record: its pocket is its index
        self.table.put(index, entry)
        if not self.is_random and index != 0 and toolno == self.tool_in_spindle:
            spindle = entry.copy()
            spindle.pocketno = self.table.get(0).pocketno
            self.table.put(0, spindle)

    def replace_table(self, table: ToolTable) -> None:
        """A reloaded tool table (EMC_TOOL_LOAD_TOOL_TABLE, EMC_TOOL_INIT; IO-013).

        The tool in the spindle stays there: on a nonrandom changer its record is copied
        again from the new table (or kept, if the new table lacks it).
        """
        if not self.is_random:
            spindle = self.table.get(0)
            table.put(0, spindle)
            index = table.find_index_for_tool(self.tool_in_spindle)
            if self.tool_in_spindle > 0 and index > 0:
                table.put(0, table.get(index))
        self.table = table
        if self.is_random:
            self.tool_in_spindle = max(0, table.get(0).toolno)

    def _check_index(self, index: int) -> None:
        if not 0 <= index < CANON_POCKETS_MAX:
            raise ToolChangeError(f"tool index {index} out of range 0..{CANON_POCKETS_MAX - 1}")
