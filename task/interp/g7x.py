"""Lathe roughing and finishing cycles G70, G71, G71.1, G71.2, G72, G72.1, G72.2.

The profile is the body of subroutine ``O<Q>``: its G0/G1/G2/G3 moves (X/Z or U/W, with A
fillets and C chamfers) are collected, not executed, then offset and cut in passes. The
geometry follows LinuxCNC's ``interp_g7x.cc`` closely, in complex numbers ``z + x*1j``, so
that the moves come out identical. The path is normalised by flipping and rotating so that
it always dives in -X while moving in -Z; ``_Swapped`` maps the moves back.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from .errors import InterpError

I = 1j  # noqa: E741
TOLERANCE = 1e-6


class G7xError(Exception):
    """A geometric failure, reported as ``G7X error: <text>``."""


def _g(value: float) -> str:
    return f"{value:g}"


def _cstr(value: complex) -> str:
    """``operator<<`` of std::complex<double>: (re,im) with 6 significant digits."""
    return f"({_g(value.real)},{_g(value.imag)})"


def _conj(z: complex) -> complex:
    return z.conjugate()


def _norm(z: complex) -> float:
    return z.real * z.real + z.imag * z.imag


# C++ multiplies and divides a complex by a double component by component; Python would
# promote the double to a complex first, which can change the sign of a zero.
def _sc(k: float, z: complex) -> complex:
    return complex(k * z.real, k * z.imag)


def _dv(z: complex, k: float) -> complex:
    return complex(z.real / k, z.imag / k)


class Segment:
    def __init__(self, start: complex, end: complex) -> None:
        self.start = start
        self.end = end
        self.finish = 0.0

    def monotonic(self) -> bool:
        return (self.end - self.start).real <= 1e-3

    def do_finish(self, prev: Segment, nxt: Segment) -> None:
        pass

    def flip_imag(self) -> None:
        self.start, self.end = _conj(self.start), _conj(self.end)

    def flip_real(self) -> None:
        self.start, self.end = -_conj(self.start), -_conj(self.end)

    def rotate(self) -> None:
        self.start, self.end = -self.start * I, -self.end * I

    def move(self, d: complex) -> None:
        self.start += d
        self.end += d

    def corner_finish(self, prev: Segment, nxt: Segment) -> complex:
        p, n = prev.dup(), nxt.dup()
        p.offset(self.finish)
        n.offset(self.finish)
        if (p.end - n.start).real > 1e-2:
            self.finish = -self.finish
            p, n = prev.dup(), nxt.dup()
            p.offset(self.finish)
            n.offset(self.finish)
        if (p.end - n.start).real > 1e-2:
            raise G7xError("Corner finish failed at " + _cstr(prev.end))
        p.intersect(n)
        center = _dv(p.end + n.start, 2.0)
        p.offset(-self.finish)
        n.offset(-self.finish)
        self.start = prev.end = p.end
        self.end = nxt.start = n.start
        return center


class Straight(Segment):
    def intersection_z(self, x: float, out: list[float]) -> None:
        s, e = self.start, self.end
        if min(s.imag, e.imag) > x + TOLERANCE or max(s.imag, e.imag) < x - TOLERANCE:
            return
        if abs((s - e).imag) < TOLERANCE:
            out.append(s.real)
            out.append(e.real)
        else:
            out.append((x - s.imag) / (e.imag - s.imag) * (e.real - s.real) + s.real)

    def climb(self, loc: list[complex], out) -> bool:
        if self.end.imag + TOLERANCE < self.start.imag:
            return True
        if abs(loc[0] - self.start) > TOLERANCE:
            raise G7xError("How did we get here?")
        out.straight_move(self.end)
        loc[0] = self.end
        return False

    def climb_only(self, loc: list[complex], out) -> None:
        if self.end.imag < self.start.imag:
            return
        found: list[float] = []
        self.intersection_z(loc[0].imag, found)
        if not found:
            return
        loc[0] = complex(found[0], loc[0].imag)
        out.straight_move(loc[0])
        out.straight_move(self.end)
        loc[0] = self.end

    def dive(self, loc: list[complex], x: float, out, fast: bool) -> bool:
        if self.start.imag <= self.end.imag + TOLERANCE:
            return True
        if x < self.end.imag:
            (out.straight_rapid if fast else out.straight_move)(self.end)
            loc[0] = self.end
            return False
        found: list[float] = []
        self.intersection_z(x, found)
        if not found:
            raise G7xError("x too large in straight dive")
        ep = complex(found[0], x)
        (out.straight_rapid if fast else out.straight_move)(ep)
        loc[0] = ep
        return False

    def draw(self, out) -> None:
        out.straight_move(self.end)

    def offset(self, distance: float) -> None:
        d = _dv(
            complex(0.0 * distance, distance) * (self.start - self.end), abs(self.start - self.end)
        )
        self.start += d
        self.end += d

    def intersect(self, other: Segment) -> None:
        other.intersect_end_straight(self)

    def intersect_end_straight(self, p: Straight) -> None:
        rot = _conj(self.start - self.end) / abs(self.start - self.end)
        ps = (p.start - self.end) * rot
        pe = (p.end - self.end) * rot
        if (ps - pe).imag == 0:
            raise G7xError("Cannot intersect parallel lines")
        f = ps.imag / (ps - pe).imag
        point = (ps + _sc(f, pe - ps)) / rot + self.end
        self.start = p.end = point

    def intersect_end_round(self, p: Round) -> None:
        if abs(self.start - p.end) < TOLERANCE:
            return
        rot = _conj(self.start - self.end) / abs(self.start - self.end)
        pe = (p.end - self.end) * rot
        pc = (p.center - self.end) * rot
        b = _norm(pc - pe) - pc.imag * pc.imag
        b = 0.0 if b < 0 else math.sqrt(b)
        s1 = (pc.real + b) / rot + self.end
        s2 = (pc.real - b) / rot + self.end
        self.start = p.end = s1 if abs(self.start - s1) < abs(self.start - s2) else s2

    def dup(self) -> Straight:
        copy = Straight.__new__(type(self))
        copy.__dict__.update(self.__dict__)
        return copy

    def radius(self) -> float:
        return abs(self.start - self.end)


class Round(Segment):
    def __init__(self, ccw: int, start: complex, center: complex, end: complex) -> None:
        super().__init__(start, end)
        self.ccw = ccw
        self.center = center

    def on_segment(self, p: complex) -> bool:
        c = self.center
        if self.ccw:
            return (_conj(self.start - c) * (p - c)).imag >= -TOLERANCE and (
                _conj(self.end - c) * (p - c)
            ).imag <= TOLERANCE
        return (_conj(self.start - c) * (p - c)).imag <= TOLERANCE and (
            _conj(self.end - c) * (p - c)
        ).imag >= -TOLERANCE

    def intersection_z(self, x: float, out: list[float]) -> None:
        r = self.start - self.center
        s = -(x - abs(r) - self.center.imag) * (x + abs(r) - self.center.imag)
        if s < -TOLERANCE:
            return
        s = math.sqrt(max(s, 0.0))
        p1 = complex((self.center + s).real, x)
        if self.on_segment(p1):
            out.append(p1.real)
        p2 = complex((self.center - s).real, x)
        if self.on_segment(p2):
            out.append(p2.real)

    def _top(self) -> complex:
        ep = self.end
        if self.end.real < self.center.real:
            ep = complex(self.center.real, self.center.imag + abs(self.start - self.center))
        return ep

    def climb(self, loc: list[complex], out) -> bool:
        if not self.ccw:
            if loc[0].real > self.center.real:
                return True
            if abs(loc[0] - self.end) > 1e-3:
                out.circular_move(self.ccw, self.center, self.end)
            loc[0] = self.end
            return False
        if loc[0].real < self.center.real:
            return True
        ep = self._top()
        if abs(loc[0] - ep) > 1e-3:
            out.circular_move(self.ccw, self.center, ep)
        loc[0] = ep
        return True

    def dive(self, loc: list[complex], x: float, out, fast: bool) -> bool:
        if abs(loc[0] - self.end) < TOLERANCE or (loc[0] - self.end).real <= TOLERANCE:
            loc[0] = self.end
            return False
        found: list[float] = []
        self.intersection_z(x, found)
        if not found:
            self.intersection_z(x - TOLERANCE, found)
        if self.ccw:
            if loc[0].real - TOLERANCE > self.center.real:
                return True
            if not found or found[-1] > self.center.real:
                out.circular_move(self.ccw, self.center, self.end)
                loc[0] = self.end
                return False
            ep = complex(found[-1], x)
            out.circular_move(self.ccw, self.center, ep)
            loc[0] = ep
            return False
        if loc[0].real <= self.center.real:
            return True
        if not found:
            out.circular_move(self.ccw, self.center, self.end)
            loc[0] = self.end
            return False
        if found[0] < self.center.real:
            return False
        ep = complex(found[0], x)
        out.circular_move(self.ccw, self.center, ep)
        loc[0] = ep
        return False

    def climb_only(self, loc: list[complex], out) -> None:
        found: list[float] = []
        self.intersection_z(loc[0].imag, found)
        if not found:
            return
        if not self.ccw:
            if found[-1] > self.center.real:
                return
            loc[0] = complex(found[-1], loc[0].imag)
            out.straight_move(loc[0])
            if abs(loc[0] - self.end) > 1e-3:
                out.circular_move(self.ccw, self.center, self.end)
            loc[0] = self.end
            return
        if found[0] < self.center.real:
            return
        loc[0] = complex(found[0], loc[0].imag)
        out.straight_move(loc[0])
        ep = self._top()
        if abs(loc[0] - ep) > 1e-3:
            out.circular_move(self.ccw, self.center, ep)
        loc[0] = ep

    def draw(self, out) -> None:
        out.circular_move(self.ccw, self.center, self.end)

    def offset(self, distance: float) -> None:
        radius = abs(self.start - self.center)
        factor = (radius + (1 if self.ccw else -1) * distance) / radius
        self.start = _sc(factor, self.start - self.center) + self.center
        self.end = _sc(factor, self.end - self.center) + self.center

    def intersect(self, other: Segment) -> None:
        other.intersect_end_round(self)

    def intersect_end_straight(self, p: Straight) -> None:
        if abs(self.start - p.end) < TOLERANCE:
            return
        rot = _conj(p.start - p.end) / abs(p.start - p.end)
        pe = (self.end - p.end) * rot
        pc = (self.center - p.end) * rot
        b = _norm(pc - pe) - pc.imag * pc.imag
        b = 0.0 if b < 0 else math.sqrt(b)
        s1 = (pc.real + b) / rot + p.end
        s2 = (pc.real - b) / rot + p.end
        self.start = p.end = s1 if abs(self.start - s1) < abs(self.start - s2) else s2

    def intersect_end_round(self, p: Round) -> None:
        a = abs(self.start - self.center)
        b = abs(p.start - p.center)
        c = abs(self.center - p.center)
        cos_b = (c * c + a * a - b * b) / 2.0 / a / c
        cos_b2 = min(cos_b * cos_b, 1.0)
        rot = complex(cos_b, math.sqrt(1 - cos_b2))
        point = _sc(a, _dv(rot * (p.center - self.center), c)) + self.center
        p.end = self.start = point

    def dup(self) -> Round:
        copy = Round.__new__(type(self))
        copy.__dict__.update(self.__dict__)
        return copy

    def radius(self) -> float:
        return min(abs(self.start - self.end), abs(self.start - self.center))

    def flip_imag(self) -> None:
        self.ccw = int(not self.ccw)
        super().flip_imag()
        self.center = _conj(self.center)

    def flip_real(self) -> None:
        self.ccw = int(not self.ccw)
        super().flip_real()
        self.center = -_conj(self.center)

    def rotate(self) -> None:
        super().rotate()
        self.center = -self.center * I

    def monotonic(self) -> bool:
        if self.finish != 0:
            return True
        entry = (self.start - self.center).imag
        exit_ = (self.end - self.center).imag
        dz = (self.end - self.start).real
        if self.ccw:
            return entry >= -1e-3 and exit_ >= -1e-3 and dz <= -1e-3
        return entry <= 1e-3 and exit_ <= 1e-3 and dz <= -1e-3

    def move(self, d: complex) -> None:
        self.start += d
        self.center += d
        self.end += d


class Fillet(Round):
    def __init__(self, distance: float, at: complex) -> None:
        super().__init__(0, at, at, at)
        self.finish = distance

    def do_finish(self, prev: Segment, nxt: Segment) -> None:
        self.center = self.corner_finish(prev, nxt)
        self.ccw = int((self.start - self.center).imag > 0 or (self.end - self.center).imag > 0)
        self.finish = 0.0


class Chamfer(Straight):
    def __init__(self, distance: float, at: complex) -> None:
        super().__init__(at, at)
        self.finish = distance

    def do_finish(self, prev: Segment, nxt: Segment) -> None:
        self.corner_finish(prev, nxt)


_SWAPS: list[Callable[[complex], complex]] = [
    lambda z: z,
    lambda z: -_conj(z),
    lambda z: _conj(z),
    lambda z: -z,
    lambda z: I * z,
    lambda z: _conj(I * z),
    lambda z: -_conj(I * z),
    lambda z: -I * z,
]
_SWAP_CCW_FLIPS = {1, 2, 5, 6}


class _Swapped:
    """Maps moves of the normalised path back to the real one."""

    def __init__(self, out, state: int) -> None:
        self.out = out
        self.map = _SWAPS[state]
        self.flip = state in _SWAP_CCW_FLIPS

    def straight_move(self, end: complex) -> None:
        self.out.straight_move(self.map(end))

    def straight_rapid(self, end: complex) -> None:
        self.out.straight_rapid(self.map(end))

    def uncompensated_rapid(self, end: complex) -> None:
        self.out.uncompensated_rapid(self.map(end))

    def circular_move(self, ccw: int, center: complex, end: complex) -> None:
        self.out.circular_move(int(not ccw) if self.flip else ccw, self.map(center), self.map(end))


class G7xPath:
    """LinuxCNC's g7x: a list of segments and the cycles made from it."""

    def __init__(self, report: Callable[[str], object]) -> None:
        self.segments: list[Segment] = []
        self.delta = 0.5
        self.escape = complex(0.3, 0.3)
        self.flip_state = 0
        self.pocket_starts: list[complex] = []
        self.report = report

    def copy(self) -> G7xPath:
        other = G7xPath(self.report)
        other.delta, other.escape, other.flip_state = self.delta, self.escape, self.flip_state
        other.segments = [s.dup() for s in self.segments]
        return other

    # ---------------------------------------------------------- normalising
    def rotate(self) -> None:
        for s in self.segments:
            s.rotate()
        self.flip_state ^= 4

    def swap(self) -> None:
        segs = self.segments
        dir_x = (segs[0].end - segs[-1].end).imag
        dir_z = (segs[0].end - segs[-1].end).real
        if dir_x > 0:
            for s in segs:
                s.flip_imag()
            self.flip_state ^= 2
        if dir_z < 0:
            for s in segs:
                s.flip_real()
            self.flip_state ^= 1

    def monotonic(self) -> None:
        first = self.segments[0]
        if (first.end - first.start).real > 0:
            first.start = complex(first.end.real, first.start.imag)
        for s in self.segments:
            if not s.monotonic():
                raise G7xError("Not monotonic")

    def do_finish(self) -> None:
        segs = self.segments
        h = 1
        while h != len(segs) - 1 and h < len(segs):
            segs[h].do_finish(segs[h - 1], segs[h + 1])
            h += 1
        k = 0
        while k < len(segs):
            if segs[k].radius() < 1e-3:
                del segs[k]
            else:
                k += 1

    # --------------------------------------------------------------- offset
    def add_distance(self, distance: float) -> None:
        segs = self.segments
        v1 = segs[0].end - segs[0].start
        v2 = segs[-1].start - segs[0].start
        if (v1 / v2).imag < 0:
            distance = -distance
        first = segs.pop(0)
        current = 0.0
        while current != distance:
            max_distance = 1e9
            for s in segs:
                max_distance = min(max_distance, s.radius() / 2)
            max_distance = min(max_distance, abs(distance - current))
            if distance < 0:
                max_distance = -max_distance
            k = 0
            while k < len(segs):
                segs[k].offset(max_distance)
                if segs[k].radius() < 1e-3:
                    del segs[k]
                else:
                    k += 1
            p = 0
            while p < len(segs) - 1:
                n = p + 1
                if (segs[p].end - segs[n].start).real > 1e-2:
                    s, e = segs[p].dup(), segs[n].dup()
                    s.offset(-max_distance)
                    e.offset(-max_distance)
                    center = _dv(s.end + e.start, 2.0)
                    segs.insert(n, Round(int(distance > 0), segs[p].end, center, segs[n].start))
                    p += 1
                p += 1
            p = 0
            while p < len(segs) - 1:
                if not segs[p].monotonic():
                    self.report("Oops " + _cstr(segs[p].start - segs[p].end) + "\n")
                    pp = p - 1 if p > 0 else len(segs) - 1
                    if segs[p].radius() < segs[pp].radius():
                        del segs[p]
                    else:
                        del segs[pp]
                    p = 0
                if segs[p].radius() < 1e-3:
                    del segs[p]
                    p = 0
                else:
                    segs[p].intersect(segs[p + 1])
                p += 1
            current += max_distance
        for p in range(len(segs) - 1):
            mid = _dv(segs[p].end + segs[p + 1].start, 2.0)
            segs[p].end = segs[p + 1].start = mid
        first.end = segs[0].start
        segs.insert(0, first)

    # --------------------------------------------------------------- cycles
    def _motion(self, out) -> _Swapped:
        return _Swapped(out, self.flip_state)

    def do_g70(self, out, x: float, z: float, d: float, e: float, p: float) -> None:
        self.segments[0].start = complex(z, x)
        path = self.copy()
        path.segments.pop(0)
        path.swap()
        for s in path.segments:
            if not s.monotonic():
                path.rotate()
                path.swap()
                break
        path.monotonic()
        if path.flip_state & 4:
            self.rotate()
        self.swap()
        self.do_finish()
        self.monotonic()
        swapped = self._motion(out)
        passes = int(p)
        while passes > 0:
            distance = (passes - 1) * (d - e) / p + e
            one = self.copy()
            one.add_distance(distance)
            # the rapid to the start point runs without cutter compensation (2.9.10)
            swapped.uncompensated_rapid(one.segments[0].start)
            swapped.straight_rapid(one.segments[0].end)
            for s in one.segments[1:-1]:
                s.draw(swapped)
            one.segments[-1].draw(swapped)
            passes -= 1

    def do_g71(
        self,
        out,
        cycle: int,
        x: float,
        z: float,
        u: float,
        w: float,
        d: float,
        i: float,
        r: float,
        do_rotate: bool = False,
    ) -> None:
        self.segments[0].start = complex(z, x)
        if do_rotate:
            self.rotate()
        self.swap()
        self.do_finish()
        self.monotonic()
        self.add_distance(d)
        displacement = complex(w, u)
        for s in self.segments:
            s.move(displacement)
        swapped = self._motion(out)
        self.delta = max(i, 2 * TOLERANCE)
        self.escape = complex(r, r)
        segs = self.segments
        swapped.straight_rapid(segs[0].start)
        if segs[-1].end.imag < segs[0].start.imag:
            ep = complex(segs[-1].end.real, segs[0].start.imag)
            segs.append(Straight(segs[-1].end, ep))
        self.pocket_starts.append(segs[0].start)
        self.pocket(cycle, segs[0].start, 0, swapped)

    def pocket(self, cycle: int, location: complex, p: int, out) -> None:
        segs = self.segments
        loc = [location]
        x = self.pocket_starts[-1].imag
        if cycle == 2:
            while p < len(segs):
                if segs[p].dive(loc, -1e9, out, p == 0):
                    break
                p += 1
            cycle = 3
        while p < len(segs):
            while x - TOLERANCE > loc[0].imag:
                x -= self.delta
            if segs[p].dive(loc, x, out, p == 0):
                if cycle == 1:
                    while p < len(segs):
                        segs[p].climb_only(loc, out)
                        p += 1
                else:
                    while p < len(segs):
                        if segs[p].climb(loc, out):
                            if cycle == 3:
                                if (
                                    loc[0].imag > self.pocket_starts[-1].imag
                                    and len(self.pocket_starts) > 1
                                ):
                                    self.pocket_starts.pop()
                                if len(self.pocket_starts) == 1:
                                    self.pocket_starts.append(loc[0])
                            self.pocket(cycle, loc[0], p, out)
                            return
                        p += 1
                return
            if abs(loc[0].imag - x) > TOLERANCE or segs[p].end == loc[0]:
                # beyond this segment (or at its end: LinuxCNC 2.9.10's fix of an
                # endless loop), on to the next
                p += 1
                continue
            for ip in range(p, len(segs)):
                found: list[float] = []
                segs[ip].intersection_z(loc[0].imag, found)
                if not found:
                    continue
                destination_z = found[0] if ip != p else found[-1]
                distance = abs(destination_z - loc[0].real)
                if destination_z - TOLERANCE > loc[0].real:
                    continue
                if distance < TOLERANCE:
                    if p == ip:
                        continue
                    if abs(loc[0] - segs[ip].start) < TOLERANCE:
                        p = ip
                        break
                    x -= self.delta
                    break
                dest = complex(destination_z, loc[0].imag)
                out.straight_move(dest)
                escape_scale = min(1.0, distance / 2 / self.escape.real)
                dest += _sc(escape_scale, self.escape)
                out.straight_rapid(dest)
                dest = loc[0] - _conj(_sc(escape_scale, self.escape))
                out.straight_rapid(dest)
                if p == 0:
                    out.straight_rapid(loc[0])
                else:
                    out.straight_move(loc[0])
                x -= self.delta
                break

    def do_g72(
        self, out, cycle: int, x: float, z: float, u: float, w: float, d: float, i: float, r: float
    ) -> None:
        self.do_g71(out, cycle, x, z, u, w, d, i, r, True)


def raise_g7x(error: G7xError) -> None:
    raise InterpError(f"G7X error: {error}") from None
