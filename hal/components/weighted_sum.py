"""weighted_sum: turn groups of bits into numbers (the inverse of bitslice):
``loadrt weighted_sum wsum_sizes=4,8`` makes summers ``wsum.0``, ``wsum.1`` (at most 8)
with inputs ``wsum.N.bit.M.in`` of weight ``wsum.N.bit.M.weight`` (default 2^M);
``wsum.N.sum`` is ``offset`` plus the weights of the true bits, held while ``hold`` is
true. One function, ``process_wsums``, for all summers."""

from __future__ import annotations

from typing import Any

from hal.api import RtComponent, module_funct, pin
from hal.components._cmath import wrap_s32
from hal.core import HalError

MAX_SUMMERS = 8


class WeightedSum(RtComponent):
    offset = pin("s32 io")
    sum_ = pin("s32 out")
    hold = pin("bit in")
    bit_in = pin("bit in", "bit.{}.in", count="size")
    weight = pin("s32 io", "bit.{}.weight", count="size")

    @classmethod
    def instances(cls, module: str, args: dict[str, str]) -> list[tuple[str, dict[str, Any]]]:
        if set(args) - {"wsum_sizes"}:
            raise HalError(f"{module}: unknown argument '{sorted(set(args) - {'wsum_sizes'})[0]}'")
        try:
            sizes = [int(word, 0) for word in args.get("wsum_sizes", "").split(",") if word]
        except ValueError:
            raise HalError(f"{module}: wsum_sizes must be numbers") from None
        sizes = sizes[:MAX_SUMMERS]
        if -1 in sizes:
            sizes = sizes[: sizes.index(-1)]
        for index, size in enumerate(sizes):
            if size < 1:
                raise HalError(f"WEIGHTED_SUM: ERROR: bad size {size} for summer {index}")
        if not sizes:
            raise HalError("WEIGHTED_SUM: ERROR: no summers specified")
        return [(f"wsum.{i}", {"size": size}) for i, size in enumerate(sizes)]

    def setup(self, size: int = 1) -> None:
        self.size = size
        for bit in range(size):
            self.weight[bit] = wrap_s32(1 << bit)

    @module_funct("", full_name="process_wsums")
    @classmethod
    def process_wsums(cls, instances: list[WeightedSum], period: int) -> None:
        for summer in instances:
            if summer.hold:
                continue
            total = summer.offset
            bits, weights = summer.bit_in, summer.weight
            for bit in range(summer.size):
                if bits[bit]:
                    total += weights[bit]
            summer.sum_ = wrap_s32(total)


COMPONENT = WeightedSum
