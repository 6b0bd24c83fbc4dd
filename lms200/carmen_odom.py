"""Odometry from a CARMEN log's ODOM lines: for laser lines that carry no pose (RAWLASER1 .. 4,
:class:`OdomPairing`), and for the laser lines of a Radish ``*-corrected`` log, whose pose fields
are a SLAM solution (:class:`CorrectedChain`).

CARMEN 0.7 loggers write each laser reading as RAWLASER (ranges and timestamps only) and the
robot's odometry as ODOM lines (about 10-20 a second); CARMEN's robot module gives a scan the
odometry interpolated at its timestamp. So does :class:`OdomPairing`: a scan stamped t takes the
pose interpolated linearly (heading along the shorter turn) between the last ODOM stamped at or
before t and the first stamped at or after it, when both lie within ``ODOM_MAX_GAP_S`` of t; else
none (a scan before the first ODOM, after the last, or across a gap in the odometry).

Scans wait for the ODOM after them: at most until a line stamped ``ODOM_MAX_GAP_S`` after them
has been read, or ``MAX_PENDING_SCANS`` wait, or their beams pass ``MAX_PENDING_BEAMS``, so memory
stays bounded.
"""

from __future__ import annotations

import dataclasses
import math
from collections import deque
from typing import Iterator

from .angles import wrap
from .records import Pose2D, Record

ODOM_MAX_GAP_S = 0.5  # s: the farthest an ODOM line may lie from a scan (either side) to give its pose
MAX_PENDING_SCANS = 256  # scans held at most while waiting for the ODOM line after them
#: beams held at most in those scans (256 of 361 beams are 92,416): 256 pose-less scans of one stamp of
#: 314,000 beams each (the longest line the reader takes) were held, 1.33 GB resident for a 188 MB log
#: (74 MB when stamped 1 s apart)
MAX_PENDING_BEAMS = 1 << 20
#: s behind the latest ODOM stamp read for which ODOM lines are kept: a laser line written late (after
#: ODOM lines stamped after it) still finds the lines around its stamp. A count of 8 lines was too
#: few (a review: 100 Hz odometry and laser lines 0.1 s late, every scan read with odom None).
ODOM_KEEP_S = 3 * ODOM_MAX_GAP_S
MAX_RECENT_ODOM = 4096  # ODOM lines kept at most, whatever their rate (memory bound on any log)


def interpolate_pose(t0: float, p0: Pose2D, t1: float, p1: Pose2D, t: float) -> Pose2D:
    """The pose at ``t`` on the line from ``p0`` (at ``t0``) to ``p1`` (at ``t1``), the heading turned
    the shorter way and wrapped to (-pi, pi]; ``p0`` where ``t1 == t0``."""
    f = 0.0 if t1 == t0 else (t - t0) / (t1 - t0)
    turn = wrap(p1[2] - p0[2])
    return (p0[0] + f * (p1[0] - p0[0]), p0[1] + f * (p1[1] - p0[1]), wrap(p0[2] + f * turn))


class OdomPairing:
    """Records of pose-less scans, handed back with odometry from the ODOM lines around them.

    Feed it every ODOM pose (:meth:`odom`) and every record (:meth:`scan`) in log order; each
    returns the records now complete, in the order given; :meth:`flush` the rest at the end.
    """

    def __init__(self) -> None:
        self.recent: deque[tuple[float, Pose2D]] = deque(maxlen=MAX_RECENT_ODOM)  # ODOM lines (stamp s, pose), ODOM_KEEP_S
        self.last_odom = -math.inf  # the latest ODOM stamp read
        self.pending: deque[Record] = deque()
        self.pending_beams = 0  # beams of the pending scans
        self.newest = -math.inf  # the latest stamp read (scans and ODOM lines)

    def odom(self, stamp: float, pose: Pose2D) -> Iterator[Record]:
        """An ODOM line (one that is not finite gives no pose)."""
        if math.isfinite(stamp) and all(map(math.isfinite, pose)):
            self.recent.append((stamp, pose))
            self.newest, self.last_odom = max(self.newest, stamp), max(self.last_odom, stamp)
            while self.recent and self.recent[0][0] < self.last_odom - ODOM_KEEP_S:
                self.recent.popleft()  # behind the latest ODOM line: a scan's own stamp (two clocks, a bad
                # stamp) emptied the buffer and raised IndexError on the next line (a review)
        return self._ready()

    def scan(self, rec: Record) -> Iterator[Record]:
        """A record without odometry: held until an ODOM line stamped at or after it is read."""
        self.pending.append(rec)
        self.pending_beams += len(rec.scan)
        self.newest = max(self.newest, rec.scan.stamp)
        return self._ready()

    def flush(self) -> Iterator[Record]:
        """The scans still waiting (the log has ended)."""
        while self.pending:
            yield self._paired(self._pop())

    def _ready(self) -> Iterator[Record]:
        while self.pending and (self.pending[0].scan.stamp <= self.last_odom or len(self.pending) > MAX_PENDING_SCANS
                                or self.pending_beams > MAX_PENDING_BEAMS
                                or self.newest - self.pending[0].scan.stamp > ODOM_MAX_GAP_S):
            yield self._paired(self._pop())

    def _pop(self) -> Record:
        rec = self.pending.popleft()
        self.pending_beams -= len(rec.scan)
        return rec

    def _paired(self, rec: Record) -> Record:
        t = rec.scan.stamp
        before = max((o for o in self.recent if o[0] <= t), default=None, key=lambda o: o[0])
        after = min((o for o in self.recent if o[0] >= t), default=None, key=lambda o: o[0])
        pose = None
        if before is not None and before[0] == t:
            pose = before[1]
        elif before is not None and after is not None and t - before[0] <= ODOM_MAX_GAP_S \
                and after[0] - t <= ODOM_MAX_GAP_S:
            pose = interpolate_pose(before[0], before[1], after[0], after[1], t)
        return rec if pose is None else dataclasses.replace(rec, odom=pose)


def compose(a: Pose2D, b: Pose2D) -> Pose2D:
    """Pose ``b`` (given in the frame of ``a``) in the frame ``a`` is given in: a (+) b."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return (a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], wrap(a[2] + b[2]))


def relative(a: Pose2D, b: Pose2D) -> Pose2D:
    """Pose ``b`` in the frame of pose ``a`` (both given in one frame): (-a) (+) b."""
    c, s = math.cos(a[2]), math.sin(a[2])
    dx, dy = b[0] - a[0], b[1] - a[1]
    return (c * dx + s * dy, -s * dx + c * dy, wrap(b[2] - a[2]))


#: s: an anchor's stamp is junk: more than this before the odometry's clock (the last ODOM line read
#: as a step; none before one). Intel's and ACES's anchors lie >= 21 s before (0, a denormal, once
#: 1.13); a raw log's ODOM lines follow each other's clock whatever the laser host's says (a review:
#: a laser clock 15 s ahead, or ODOM lines all stamped 0, froze the odometry of a raw log)
ANCHOR_STAMP_GAP_S = 10.0
CONFIRMING_ANCHORS = 2  # anchors read in a row before a missing or foreign one is taken for one


class CorrectedChain:
    """Raw odometry and corrected poses for the laser lines of a Radish ``*-corrected`` log.

    Such a log (Intel Research Lab, ACES: a SLAM solution written back into the log) gives every
    FLASER / RLASER line the corrected pose in its pose fields (both the laser and the odometry
    pose), and writes after each one an ODOM line at exactly that pose, its stamp junk (more than
    ``ANCHOR_STAMP_GAP_S`` before the odometry's own clock, the last ODOM step's stamp, and before the
    laser line's own stamp: 21 s or more in both; both logs
    begin with ODOM lines, but one cut before a scan does not: there the first scan's anchor is
    judged by the stamps of the next ODOM line and of the scan itself): the odometry restarts at
    that anchor, and the ODOM lines up to the next laser line are the robot's raw odometry from it.
    So the odometry between two scans is the last ODOM pose before the second seen from the first's anchor; chained from
    the first anchored scan's pose, the scans get a raw odometry trajectory (dead reckoning, in
    the corrected frame at the start), and their pose fields become ``Record.corrected``.
    Measured: every laser line of the Intel (910) and ACES (440) logs has its anchor; at the next
    scan the odometry and the corrected pose differ by a median 5 cm and 0.7-2.6 deg (the
    odometry's drift over one 0.7-1 m step).

    Feed every laser record of the kind read (:meth:`laser`, its ``odom`` being the line's pose
    fields) and every ODOM line (:meth:`odom`) in log order; each returns the records now
    complete, in log order; :meth:`flush` the last at the end. Once a chain runs (``CONFIRMING_ANCHORS``
    anchors read in a row, so that one coincidence in a raw log is not taken for a corrected log):

    - a scan whose anchor is missing (a cut log, a damaged anchor skipped) keeps the chained
      odometry and its pose fields as its corrected pose, and the chain goes on from it, as if
      its anchor had been read;
    - (once an anchor and a step have been read) an ODOM line with a junk stamp that is no held scan's anchor
      (the anchor of another laser kind's line, or of a laser line skipped as malformed) moves the
      chain's anchor there, with the odometry at that point, so the ODOM lines after it are read
      from it;
    - odometry that is not finite (poses near 1e308) ends the chain.

    Otherwise (a raw log) a scan without its anchor is handed back as read (its pose fields as
    odometry, no corrected pose), and the chain starts again at the next anchor. A chain's first
    anchored scan is held until the chain runs: should the next scan have no anchor, it too is handed
    back as read, so a raw log never has a corrected pose from one coincidence (a clock set back
    100 s while the robot stood read the scan before the jump as corrected, and ``info`` said
    "corrected poses 1 scans"), and the chain is confirmed only if an ODOM step on the odometry's
    own clock came between its first two anchors (the odometry host's clock alone set back, the
    robot standing, gave an "anchor" after every scan with none between); without one the first
    scan is handed back as read and the chain starts again at the second. Holds two records at most.
    """

    def __init__(self) -> None:
        self.pending: tuple[Record, Pose2D] | None = None  # a laser record and its chained odometry
        self.anchor: tuple[Pose2D, Pose2D] | None = None  # the last anchor (corrected pose, odometry there)
        self.last_odom: Pose2D | None = None  # the last ODOM pose after that anchor
        self.step_stamp: float | None = None  # the stamp of the last ODOM line read as a step (s)
        self.in_a_row = 0  # anchors read in a row (CONFIRMING_ANCHORS: the chain runs)
        self.stepped = False  # an ODOM step read (on the odometry's clock) since the chain's first anchor
        #: an ODOM line (pose, stamp s) at the held scan's pose read before any ODOM step: no clock yet
        #: judges its stamp, so it waits for the next ODOM line's (:meth:`_judge_first`)
        self.first: tuple[Pose2D, float] | None = None
        #: a chain's first anchored scan, as read and anchored: given anchored once the chain runs, as
        #: read if it ends first
        self.tentative: tuple[Record, Record] | None = None

    def laser(self, rec: Record) -> Iterator[Record]:
        """A laser record of the kind read; held until the ODOM line after it is read."""
        yield from self._settle()
        if rec.odom is None:  # the log says its pose fields are no odometry (PARAM lmsbench_odometry)
            yield from self._end()
            yield rec
            return
        odom = rec.odom if self.anchor is None else self._odometry_now()  # a chain starts at the scan's own pose
        if not all(map(math.isfinite, odom)):
            yield from self._end()
            odom = rec.odom
        self.pending = (rec, odom)

    def odom(self, pose: Pose2D, stamp: float) -> Iterator[Record]:
        """An ODOM line's pose and stamp (s): the anchor of the held record, another line's anchor,
        or a step of the odometry."""
        if self.first is not None:
            yield from self._judge_first(stamp)
        if (self.step_stamp is None and self.pending is not None and pose == self.pending[0].odom
                and all(map(math.isfinite, pose))):
            self.first = (pose, stamp)  # the held scan's anchor, if the next ODOM line's stamp says its stamp is junk
            return
        # judged by the odometry's own clock (a raw log's ODOM lines follow it, whatever the laser's
        # says), so not before an ODOM step has been read (Intel and ACES begin with ODOM lines)
        junk = self.step_stamp is not None and not stamp >= self.step_stamp - ANCHOR_STAMP_GAP_S  # nan too
        # an anchor's stamp is junk by the scan's own clock too (Intel's and ACES's lie 21 s or more before
        # their laser line's), as _judge_first asks: a raw log whose clock jumped back (two runs joined, a
        # clock set back) had every later ODOM line junk by the odometry's clock, and one at a standing
        # robot's pose, its laser line's odometry, was taken for an anchor: the scans from there on were
        # read as a corrected log's, their odometry frozen (3 m off after 10 s) and their pose fields corrected poses
        if (self.pending is not None and junk and pose == self.pending[0].odom
                and not stamp >= self.pending[0].scan.stamp - ANCHOR_STAMP_GAP_S):
            rec, odom = self.pending
            self.pending = None
            if 0 < self.in_a_row < CONFIRMING_ANCHORS and not self.stepped:
                # no ODOM step on the odometry's clock since the chain's first anchor: that clock jumped
                # back (the odometry host's alone set back, while the robot stood), as a corrected log's
                # never does (steps stamped by it follow every anchor); 51 of 100 scans read "corrected",
                # their odometry frozen. The first scan as read, the clock goes on from this line, and a
                # chain starts at this scan: handing both back as read started chains only in pairs, so
                # a corrected log whose raw ODOM lines are sparse (none between some scans) read raw
                yield from self._end()
                self._step(pose, stamp)
                yield from self._anchored(rec, pose)  # its own pose: a new chain starts there
                return
            yield from self._anchored(rec, odom)
            return
        yield from self._settle()
        if not all(map(math.isfinite, pose)):
            return
        if junk and self.anchor is not None:
            odom = self._odometry_now()  # another line's anchor (junk by the odometry's own clock): the
            if all(map(math.isfinite, odom)):  # odometry restarts at its pose
                self.anchor, self.last_odom = (pose, odom), None
            else:
                yield from self._end()
            return
        self._step(pose, stamp)

    @property
    def running(self) -> bool:
        """A chain runs: CONFIRMING_ANCHORS anchors read in a row, none missed since."""
        return self.anchor is not None and self.in_a_row >= CONFIRMING_ANCHORS

    def flush(self) -> Iterator[Record]:
        """The records held, at the end of the log: the last as :meth:`_settle` gives it, and a
        chain's first anchored scan whose chain never ran as read."""
        yield from self._settle()
        yield from self._release()

    def _settle(self) -> Iterator[Record]:
        """The held record, with no anchor after it: anchored all the same once a chain runs (its
        pose fields are its corrected pose), else as read (the chain ends)."""
        if self.first is not None:  # no ODOM line after it to judge it: a step, as read
            yield from self._judge_first(math.nan)
            return
        if self.pending is not None:
            rec, odom = self.pending
            self.pending = None
            if self.running:
                yield from self._anchored(rec, odom)
            else:
                yield from self._end()
                yield rec

    def _judge_first(self, clock: float) -> Iterator[Record]:
        """Settle :attr:`first` by ``clock``, the stamp of the ODOM line after it (nan: none came
        before the next laser line or the end): its stamp more than ANCHOR_STAMP_GAP_S before that
        and before the held scan's own stamp makes it the scan's anchor (a log that begins with a
        laser line: Intel or ACES cut before their first scan); else it is a step, as any ODOM line
        before the first step was read (a raw log's ODOM line at a standing robot's pose, or ODOM
        lines all stamped alike)."""
        assert self.first is not None and self.pending is not None
        pose, stamp = self.first
        self.first = None
        rec, odom = self.pending
        if stamp < clock - ANCHOR_STAMP_GAP_S and stamp < rec.scan.stamp - ANCHOR_STAMP_GAP_S:
            self.pending = None
            yield from self._anchored(rec, odom)
            return
        yield from self._settle()
        self._step(pose, stamp)

    def _step(self, pose: Pose2D, stamp: float) -> None:
        """An ODOM line read as a step of the odometry: its pose, and its stamp as the odometry's clock."""
        self.last_odom = pose
        self.stepped = True
        if math.isfinite(stamp):
            self.step_stamp = stamp

    def _end(self) -> Iterator[Record]:
        """The chain ends: a first anchored scan still held, its chain never run, as read."""
        self.anchor, self.last_odom, self.in_a_row = None, None, 0
        yield from self._release()

    def _release(self) -> Iterator[Record]:
        if self.tentative is not None:
            rec = self.tentative[0]
            self.tentative = None
            yield rec

    def _anchored(self, rec: Record, odom: Pose2D) -> Iterator[Record]:
        """``rec`` with its anchor read: held while it is its chain's first, else given (after the
        first, once the chain runs)."""
        assert rec.odom is not None
        self.anchor, self.last_odom = (rec.odom, odom), None
        self.in_a_row += 1
        if self.in_a_row == 1:
            self.stepped = False
        done = dataclasses.replace(rec, odom=odom, corrected=rec.odom)
        if self.in_a_row < CONFIRMING_ANCHORS:
            self.tentative = (rec, done)
            return
        if self.tentative is not None:
            yield self.tentative[1]
            self.tentative = None
        yield done

    def _odometry_now(self) -> Pose2D:
        """The chained odometry at the last ODOM line read (at the anchor when none since)."""
        assert self.anchor is not None
        at, odom_at = self.anchor
        return compose(odom_at, relative(at, self.last_odom if self.last_odom is not None else at))
