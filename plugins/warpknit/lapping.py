"""Lapping notation: the knitting sequence of one guide bar, course by course.

A sequence such as ``1-0/1-2`` lists, for each course, the pair of guide positions ``a-b`` that
the overlap is made between (PHYSICS §1.2). The integers name the *needle gaps*, numbered across
the needle bed; gap ``n`` and gap ``n + 1`` bracket needle ``n``, so an overlap ``a-b`` with
``|a - b| = 1`` wraps needle ``min(a, b)``. The underlap of course ``i`` runs on the technical
back from where overlap ``i`` ended (``b_i``) to where overlap ``i + 1`` starts (``a_{i+1}``,
cyclically), so its signed shift is ``a_{i+1} - b_i`` needle spaces.

Open and closed laps [L] (D. J. Spencer, *Knitting Technology*, 3rd ed., Woodhead 2001,
ch. 26-27): the lap of course ``i`` is **closed** when the underlap that follows it shogs in the
direction *opposite* to its overlap, ``sign(a_{i+1} - b_i) = -sign(b_i - a_i)``, so the thread
wraps the needle at the back as well as the front and its two legs cross; it is **open** when the
underlap continues in the *same* direction as the overlap, or when there is no underlap
(``a_{i+1} = b_i``). So ``1-0/1-2`` is closed-lap tricot, ``0-1/2-1`` open-lap tricot,
``1-0/0-1`` open-lap pillar and ``1-0/1-0`` closed-lap pillar.

Accepted spellings: courses separated by ``/``; the repeat may end with ``/`` or ``//`` (the
chain-link notation marks the end of the repeat with ``//``); spaces anywhere between tokens;
an en dash may stand for the hyphen. Anything else is a ``LappingSyntaxError`` pointing at the
offending character.
"""

from __future__ import annotations

from typing import Literal, NamedTuple

#: Stitch families told apart by where the loops of one repeat sit (see ``classify``).
StitchClass = Literal["pillar", "tricot", "cord", "satin", "velvet", "atlas", "custom"]
LapKind = Literal["open", "closed"]

_HYPHENS = "-\u2013"


class LappingSyntaxError(ValueError):
    """A knitting sequence that cannot be read.

    ``position`` is the 0-based character index of the offending character in ``text``
    (``len(text)`` when the sequence ends too early); ``str()`` shows the text with a caret.
    """

    def __init__(self, message: str, text: str, position: int) -> None:
        self.message = message
        self.text = text
        self.position = position
        super().__init__(f"{message} at character {position + 1}\n{self.caret_diagram()}")

    def caret_diagram(self) -> str:
        """The sequence on one line and a caret under the offending character on the next."""
        return f"  {self.text}\n  {' ' * self.position}^"


# Records without cached properties or dataclasses.replace callers are named tuples: immutable
# and compared by value as frozen dataclasses are, but creating a dataclass execs its generated
# methods, which every start-up pays (`materials list` validates the library; issue 15l).
class Course(NamedTuple):
    """One course of a guide bar's lapping movement (lengths in needle spaces)."""

    #: Needle gaps the overlap is made from and to, (a, b).
    overlap: tuple[int, int]
    #: Signed underlap shift [needle spaces] from the end of this overlap to the start of the
    #: next (positive towards higher gap numbers); 0 for no underlap.
    underlap_shift: int
    #: Open or closed lap (module docstring).
    lap: LapKind

    @property
    def overlap_shift(self) -> int:
        """Signed overlap shift b - a [needle spaces]."""
        return self.overlap[1] - self.overlap[0]

    @property
    def needle(self) -> int:
        """The needle the loop is formed on (the lower of the two gaps bracketing it)."""
        return min(self.overlap)


class LappingSequence(NamedTuple):
    """A parsed knitting sequence: one repeat of a guide bar's courses."""

    text: str
    courses: tuple[Course, ...]

    @property
    def course_count(self) -> int:
        """Courses in one repeat of the sequence."""
        return len(self.courses)

    @property
    def underlap_shifts(self) -> tuple[int, ...]:
        """Signed underlap shift of each course [needle spaces]."""
        return tuple(c.underlap_shift for c in self.courses)

    @property
    def classification(self) -> StitchClass:
        """Stitch family of the sequence (``classify``)."""
        return classify(self.courses)

    @property
    def gap_span(self) -> tuple[int, int]:
        """Lowest and highest needle gap the guide visits."""
        gaps = [g for c in self.courses for g in c.overlap]
        return min(gaps), max(gaps)

    def describe(self) -> str:
        """Human-readable summary, e.g. ``1-0/1-2 (tricot, closed laps)``."""
        laps = sorted({c.lap for c in self.courses})
        lap_text = "mixed laps" if len(laps) > 1 else f"{laps[0]} laps"
        return f"{self.normalised()} ({self.classification}, {lap_text})"

    def normalised(self) -> str:
        """The sequence in canonical spelling: ``a-b/c-d``."""
        return "/".join(f"{c.overlap[0]}-{c.overlap[1]}" for c in self.courses)


#: Two-course families by how many needles apart their loops are (1x1 ... 4x1 [L]).
_TWO_COURSE_FAMILIES: dict[int, StitchClass] = {1: "tricot", 2: "cord", 3: "satin", 4: "velvet"}


def classify(courses: tuple[Course, ...]) -> StitchClass:
    """Stitch family from the needles the loops are formed on over one repeat.

    The sequence is first reduced to its shortest repeating part. Every overlap must wrap
    exactly one needle, otherwise the result is ``custom``. Then: all loops on one needle is
    ``pillar`` (chain), whatever the laps; two courses whose loops are 1, 2, 3 or 4 needles
    apart are ``tricot``, ``cord``, ``satin`` or ``velvet`` (1x1 ... 4x1 [L]); three or more
    courses whose loop needle climbs monotonically for a while and then returns, with at least
    one run of two or more steps, is ``atlas``; anything else is ``custom``.
    """
    pairs = [c.overlap for c in courses]
    period = next(p for p in range(1, len(pairs) + 1) if _repeats_with(pairs, p))
    core = courses[:period]
    if any(abs(c.overlap_shift) != 1 for c in core):
        return "custom"
    needles = [c.needle for c in core]
    if len(set(needles)) == 1:
        return "pillar"
    if period == 2:
        return _TWO_COURSE_FAMILIES.get(abs(needles[1] - needles[0]), "custom")
    steps = [needles[(i + 1) % period] - needles[i] for i in range(period)]
    if any(s == 0 for s in steps):
        return "custom"
    turns = sum(1 for i in range(period) if (steps[i] > 0) != (steps[i - 1] > 0))
    longest_run = _longest_cyclic_run([s > 0 for s in steps])
    return "atlas" if turns == 2 and longest_run >= 2 else "custom"


def _repeats_with(pairs: list[tuple[int, int]], period: int) -> bool:
    return len(pairs) % period == 0 and all(
        pairs[i] == pairs[i % period] for i in range(len(pairs))
    )


def _longest_cyclic_run(flags: list[bool]) -> int:
    doubled = flags + flags
    best = run = 0
    for i, f in enumerate(doubled):
        run = run + 1 if i > 0 and f == doubled[i - 1] else 1
        best = max(best, run)
    return min(best, len(flags))


def parse_lapping(text: str) -> LappingSequence:
    """Parse a knitting sequence in lapping notation (module docstring for the grammar).

    Raises ``LappingSyntaxError`` (a ``ValueError``) with the position of the first character
    that does not fit, or of an overlap that does not move the guide (``a-a`` wraps no needle).
    """
    reader = _Reader(text)
    pairs: list[tuple[int, int]] = []
    reader.skip_spaces()
    if reader.at_end():
        raise LappingSyntaxError("empty knitting sequence", text, reader.pos)
    while True:
        a = reader.integer("a needle gap number")
        reader.skip_spaces()
        reader.expect(_HYPHENS, "'-' between the two needle gaps of an overlap")
        reader.skip_spaces()
        b_pos = reader.pos
        b = reader.integer("a needle gap number")
        if a == b:
            raise LappingSyntaxError(
                f"overlap {a}-{b} wraps no needle (its two gaps must differ)", text, b_pos
            )
        pairs.append((a, b))
        reader.skip_spaces()
        if reader.at_end():
            break
        reader.expect("/", "'/' between courses")
        reader.skip_spaces()
        if reader.at_end():
            break  # trailing '/'
        if reader.peek() == "/":
            reader.pos += 1
            reader.skip_spaces()
            if not reader.at_end():
                raise LappingSyntaxError(
                    "'//' ends the repeat; nothing may follow it", text, reader.pos
                )
            break
    return LappingSequence(text=text, courses=_courses(pairs))


def _courses(pairs: list[tuple[int, int]]) -> tuple[Course, ...]:
    courses = []
    for i, (a, b) in enumerate(pairs):
        next_a = pairs[(i + 1) % len(pairs)][0]
        shift = next_a - b
        overlap_sign = (b > a) - (b < a)
        underlap_sign = (shift > 0) - (shift < 0)
        lap: LapKind = "closed" if underlap_sign == -overlap_sign else "open"
        courses.append(Course(overlap=(a, b), underlap_shift=shift, lap=lap))
    return tuple(courses)


class _Reader:
    """Cursor over the text; every failure reports the cursor position."""

    def __init__(self, text: str) -> None:
        self.text = text
        self.pos = 0

    def at_end(self) -> bool:
        return self.pos >= len(self.text)

    def peek(self) -> str:
        return self.text[self.pos]

    def skip_spaces(self) -> None:
        while not self.at_end() and self.peek() in " \t":
            self.pos += 1

    def _fail(self, wanted: str) -> LappingSyntaxError:
        found = "end of sequence" if self.at_end() else repr(self.peek())
        return LappingSyntaxError(f"expected {wanted}, found {found}", self.text, self.pos)

    def integer(self, wanted: str) -> int:
        start = self.pos
        while not self.at_end() and self.peek() in "0123456789":
            self.pos += 1
        if self.pos == start:
            raise self._fail(wanted)
        return int(self.text[start : self.pos])

    def expect(self, chars: str, wanted: str) -> None:
        if self.at_end() or self.peek() not in chars:
            raise self._fail(wanted)
        self.pos += 1
