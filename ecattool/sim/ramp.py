"""The reference generator of a profile move: a trapezoidal velocity profile planned when the set-point is taken
(profile velocity 6081h, profile acceleration 6083h, profile deceleration 6084h — Technosoft has no 6084h and
ramps down with 6083h), and the jerk-limited ramp (S-curve) the manuals define on top of it.

Everything is in increments, increments per second and per second² (exact fractions). A trapezoid is a list of
constant-acceleration segments; :class:`SCurve` is the trapezoid's per-cycle steps averaged over the jerk time
(a moving average over ``Tj`` of a trapezoidal velocity profile is the jerk-limited profile with jerk
``a / Tj``: the acceleration becomes a trapezoid, the velocity an S, and the distance stays the same).
"""

from __future__ import annotations

from collections import deque
from fractions import Fraction
from math import isqrt

_ZERO = Fraction(0)


def _sqrt(x: Fraction) -> Fraction:
    """A square root to 2^-24 relative precision, as a fraction (the peak of a triangular move is irrational)."""
    if x <= 0:
        return _ZERO
    scale = 1 << 48
    return Fraction(isqrt(int(x * scale * scale)), scale)


class Trapezoid:
    """Constant-acceleration segments (start time, start position, start velocity, acceleration) from ``start``
    at velocity ``v0`` to rest at ``target``, never faster than ``vmax``, speeding up at ``acc`` and slowing
    down at ``dec``."""

    __slots__ = ("segments", "target", "duration", "_ints")

    def __init__(self, start: Fraction, v0: Fraction, target: Fraction, vmax: Fraction, acc: Fraction,
                 dec: Fraction) -> None:
        self.target = target
        self.segments: list[tuple[Fraction, Fraction, Fraction, Fraction]] = []
        vmax, acc, dec = abs(vmax), abs(acc), abs(dec)
        t, p, v = _ZERO, start, v0

        def add(duration: Fraction, a: Fraction) -> None:
            nonlocal t, p, v
            if duration <= 0:
                return
            self.segments.append((t, p, v, a))
            p += v * duration + a * duration * duration / 2
            v += a * duration
            t += duration

        for _ in range(3):  # at most: brake (moving away or too fast to stop), then the move itself
            dist = target - p
            sign = 1 if dist > 0 or (dist == 0 and v > 0) else -1
            u, d = v * sign, abs(dist)
            if u < 0:  # moving away from the target: stop first
                add(-u / dec, sign * dec)
                continue
            if u * u > 2 * dec * d:  # cannot stop in time: stop beyond the target, then come back
                add(u / dec, -sign * dec)
                continue
            if u > vmax:  # faster than the profile velocity (6081h lowered during the move)
                add((u - vmax) / dec, -sign * dec)
                continue
            peak = min(vmax, _sqrt((2 * acc * dec * d + dec * u * u) / (acc + dec)))
            peak = max(peak, u)
            d_up = (peak * peak - u * u) / (2 * acc)
            d_down = peak * peak / (2 * dec)
            add((peak - u) / acc, sign * acc)
            if peak > 0:
                add(max(_ZERO, d - d_up - d_down) / peak, _ZERO)
            add(peak / dec, -sign * dec)
            break
        self.duration = t
        #: the segments as integers (each value's numerator and denominator) for :meth:`at`, every cycle
        self._ints = [(t0.numerator, t0.denominator, p0.numerator, p0.denominator, v0.numerator, v0.denominator,
                       a.numerator, a.denominator) for t0, p0, v0, a in self.segments]

    def at(self, time: Fraction) -> tuple[Fraction, Fraction]:
        """(position, velocity) ``time`` seconds after the plan started; at rest on the target at the end."""
        if time >= self.duration or not self.segments:
            return self.target, _ZERO
        # the segment running at ``time``: the last that starts at or before it (t0 <= time, in integers)
        n, d = time.numerator, time.denominator
        ints = self._ints
        seg = ints[0]
        for s in ints:
            if s[0] * d > n * s[1]:
                break
            seg = s
        tn, td, pn, pd, vn, vd, an, ad = seg
        # tau = time - t0; p0 + v0 tau + a tau^2 / 2 and v0 + a tau over common denominators, made a Fraction
        # once (the same values as the Fraction arithmetic, which normalises after every operation)
        un, ud = n * td - tn * d, d * td
        position = Fraction(pn * vd * ad * 2 * ud * ud + vn * un * pd * ad * 2 * ud + an * un * un * pd * vd,
                            pd * vd * ad * 2 * ud * ud)
        return position, Fraction(vn * ad * ud + an * un * vd, vd * ad * ud)


#: the most smoothing windows :func:`jerk_window` tries (a jerk so small that the best window is longer is served
#: by the best of these; at a 1 ms cycle, 20 s of jerk time)
MAX_JERK_WINDOWS = 20_000


def _cycles(ramp: Trapezoid, window: int, dt: Fraction) -> int:
    """The cycles :class:`ProfileMove` takes for ``ramp`` smoothed over ``window`` cycles (see its ``done``)."""
    n = -((-ramp.duration) // dt)  # ceil
    return int(n) + (window if window > 1 else 0)


def _within(acc: Fraction, dec: Fraction, limit: Fraction) -> tuple[Fraction, Fraction]:
    """Acceleration and deceleration, each at most as given, with a mean of at most ``limit``: the smaller one
    first up to ``limit``, the other up to what the mean leaves (the split that makes the shortest move)."""
    if acc <= dec:
        a = min(acc, limit)
        return a, min(dec, 2 * limit - a)
    d = min(dec, limit)
    return min(acc, 2 * limit - d), d


def jerk_window(start: Fraction, v0: Fraction, target: Fraction, vmax: Fraction, acc: Fraction, dec: Fraction,
                jerk: Fraction, dt: Fraction) -> tuple[int, Fraction, Fraction]:
    """The smoothing window (cycles) and the accelerations (increments/s²) of the fastest jerk-limited move whose
    jerk stays within ``jerk`` (increments/s³; HDT 2011h): a window of ``w`` cycles turns an acceleration ``a``
    into a ramp of jerk ``a / (w dt)``; the window allows a mean of 6083h and 6084h of at most ``jerk w dt`` (the
    one window serves both ramps, and with the mean the move takes as long as the jerk-limited ramp of the
    manual, which adds a / 2J + d / 2J to the trapezoid). A large 6083h
    with a small jerk is not reached (the acceleration ramp turns back before it: HDT §4.07.9, "a higher jerk
    value ... reduce[s] the time needed for the positioning"): the window is the one of the fewest cycles, so a
    larger acceleration, deceleration or velocity never makes the move longer (each window's cycle count does not
    grow with them, and the choice is the least over the same windows)."""
    acc, dec, jerk = abs(acc), abs(dec), abs(jerk)
    if jerk <= 0 or dt <= 0 or acc <= 0:
        return 1, acc, dec
    best: tuple[int, int, Fraction, Fraction] | None = None
    top = max(acc, dec or acc)
    for w in range(1, MAX_JERK_WINDOWS + 1):
        limit = jerk * w * dt
        a, d = _within(acc, dec or acc, limit)
        n = _cycles(Trapezoid(start, v0, target, vmax, a, d), w, dt)
        if best is None or n < best[0]:
            best = (n, w, a, d)
        if limit >= top or w >= best[0]:  # a longer window only adds cycles from here on
            break
    assert best is not None
    return best[1], best[2], best[3]


class ProfileMove:
    """One profile move as the drive's reference generator runs it, cycle by cycle: the trapezoid, smoothed
    over ``jerk_time`` seconds where the profile is jerk-limited (0: a plain trapezoid), or, with ``jerk``
    (increments/s³), over the window :func:`jerk_window` chooses for that jerk."""

    __slots__ = ("ramp", "elapsed", "window", "steps", "total", "raw", "position")

    def __init__(self, start: Fraction, v0: Fraction, target: Fraction, vmax: Fraction, acc: Fraction,
                 dec: Fraction, jerk_time: Fraction, dt: Fraction, jerk: Fraction | None = None) -> None:
        if jerk:
            window, acc, dec = jerk_window(start, v0, target, vmax, acc, dec, jerk, dt)
            jerk_time = window * dt if window > 1 else _ZERO
        self.ramp = Trapezoid(start, v0, target, vmax, acc, dec)
        self.elapsed = _ZERO
        self.window = max(1, round(jerk_time / dt)) if jerk_time > 0 and dt > 0 else 1
        self.steps: deque[Fraction] = deque([v0 * dt] * (self.window - 1) if self.window > 1 else ())
        self.total = sum(self.steps, _ZERO)  # the window's sum, kept as steps enter and leave
        self.raw = start  # the trapezoid's own position
        self.position = start

    @property
    def target(self) -> Fraction:
        return self.ramp.target

    def step(self, dt: Fraction) -> tuple[Fraction, Fraction, bool]:
        """Advance one cycle: (position, velocity, done)."""
        self.elapsed += dt
        raw, now = self.ramp.at(self.elapsed)
        step = raw - self.raw if self.window != 1 else _ZERO  # only the smoothing window uses the step
        self.raw = raw
        if self.window == 1:
            self.position = raw
            velocity = now
        else:
            self.steps.append(step)
            self.total += step
            while len(self.steps) > self.window:
                self.total -= self.steps.popleft()
            moved = self.total / self.window
            self.position += moved
            velocity = moved / dt if dt else _ZERO
        done = self.elapsed >= self.ramp.duration and (
            self.window == 1 or self.elapsed >= self.ramp.duration + self.window * dt)
        if done:
            self.position = self.ramp.target
            velocity = _ZERO
        return self.position, velocity, done


def profile_time(distance: Fraction, vmax: Fraction, acc: Fraction, dec: Fraction) -> Fraction:
    """The time a trapezoidal move of ``distance`` from rest to rest takes (the shortest the profile allows)."""
    if distance == 0:
        return _ZERO
    return Trapezoid(_ZERO, _ZERO, abs(distance), vmax, acc, dec).duration
