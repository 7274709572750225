"""Check a drive's EEPROM against a ``.sw`` image and reload what differs (manual §1.1.10, §17.4.1).

``verify`` asks the drive for the checksum of each block's address range (2069h := end<<16 | start, then
read 206Ah) and compares it with the block's checksum. ``download`` verifies, writes only the blocks that
differ, verifies those again, and resets the drive (2080h, no SDO reply) only when every block checks out.
A write that fails (SDO abort, timeout, power loss) does not stop the run: the block is reported with the
error and the verify step after writing shows it as different, so running the download again repairs it.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from ecattool.errors import SdoTimeout, TargetError
from ecattool.od.model import EcState
from ecattool.sw.image import Block, SwImage
from ecattool.sw.plan import OBJ_CHECKSUM, OBJ_CHECKSUM_RANGE, OBJ_CONFIG, block_commands, reset_command
from ecattool.target.base import SlaveTarget

#: progress(words_done, words_total, block_being_written)
Progress = Callable[[int, int, Block], None]


@dataclass(frozen=True, slots=True)
class BlockCheck:
    block: Block
    expected: int
    actual: int | None  # None when the drive did not answer
    error: str | None = None

    @property
    def ok(self) -> bool:
        return self.error is None and self.actual == self.expected

    @property
    def start(self) -> int:
        return self.block.start

    @property
    def end(self) -> int:
        return self.block.end

    def to_json(self) -> dict[str, Any]:
        b = self.block
        return {"start": b.start, "end": b.end, "count": b.count, "expected": self.expected,
                "actual": self.actual, "ok": self.ok, "error": self.error}

    def describe(self) -> str:
        b = self.block
        where = f"block 0x{b.start:04X}..0x{b.end:04X} ({b.count} words)"
        if self.error:
            return f"{where}: {self.error}"
        if self.ok:
            return f"{where}: checksum 0x{self.expected:04X} ok"
        return f"{where}: drive checksum 0x{self.actual:04X}, file 0x{self.expected:04X}"


def _u32(value: int) -> bytes:
    return value.to_bytes(4, "little")


def check_block(block: Block, target: SlaveTarget) -> BlockCheck:
    """Have the drive sum the block's range (2069h) and read the result (206Ah)."""
    try:
        target.sdo_download(OBJ_CHECKSUM_RANGE, 0, _u32(block.checksum_request))
        data = target.sdo_upload(OBJ_CHECKSUM, 0, size=2)  # 206Ah: UNSIGNED16 (§17.2.6)
    except TargetError as exc:
        return BlockCheck(block, block.checksum, None, str(exc))
    return BlockCheck(block, block.checksum, int.from_bytes(data[:2], "little"))


def ensure_mailbox(target: SlaveTarget) -> None:
    """SDOs need the mailbox: bring a slave that is in INIT (just powered on or reset) to PRE-OP."""
    if target.state() is EcState.INIT:
        target.request_state(EcState.PREOP)


def verify(image: SwImage, target: SlaveTarget, blocks: Sequence[Block] | None = None) -> list[BlockCheck]:
    """Compare the drive's checksum of every block range with the image, block by block."""
    ensure_mailbox(target)
    return [check_block(b, target) for b in (image.blocks if blocks is None else blocks)]


@dataclass
class DownloadReport:
    before: list[BlockCheck]
    written: list[Block] = field(default_factory=list)
    write_errors: dict[int, str] = field(default_factory=dict)  # block start -> error of the write
    after: list[BlockCheck] = field(default_factory=list)
    reset: bool = False

    @property
    def ok(self) -> bool:
        return not self.write_errors and all(c.ok for c in self.after)

    @property
    def failed(self) -> list[BlockCheck]:
        return [c for c in self.after if not c.ok]

    def to_json(self) -> dict[str, Any]:
        return {
            "ok": self.ok,
            "before": [c.to_json() for c in self.before],
            "written": [{"start": b.start, "end": b.end, "count": b.count,
                         "error": self.write_errors.get(b.start)} for b in self.written],
            "after": [c.to_json() for c in self.after],
            "reset": self.reset,
        }


def write_block(block: Block, target: SlaveTarget, mode: int = 16,
                on_word: Callable[[int], None] | None = None) -> None:
    """Program one block (2064h, then 2065h per word or word pair). Raises TargetError on failure."""
    width = 1
    for cmd in block_commands(block, mode):
        target.sdo_download(cmd.index, cmd.subindex, cmd.data, expect_reply=cmd.expect_reply)
        if cmd.index == OBJ_CONFIG:
            width = 2 if cmd.int_value & 1 else 1
        elif on_word is not None:
            on_word(width)


def reset_drive(target: SlaveTarget) -> None:
    cmd = reset_command()
    try:
        target.sdo_download(cmd.index, cmd.subindex, cmd.data, expect_reply=False)
    except SdoTimeout:
        pass  # the drive resets instead of answering


def download(image: SwImage, target: SlaveTarget, progress: Progress | None = None, mode: int = 16,
             reset: bool = True, force: bool = False) -> DownloadReport:
    """Write the blocks whose drive checksum differs (all with ``force``), verify them, then reset."""
    before = verify(image, target)
    todo = [c.block for c in before if force or not c.ok]
    report = DownloadReport(before, written=todo)
    total = sum(b.count for b in todo)
    done = 0
    for b in todo:
        def advance(n: int, b: Block = b) -> None:
            nonlocal done
            done = min(total, done + n)
            if progress is not None:
                progress(done, total, b)

        start_done = done
        try:
            ensure_mailbox(target)
            write_block(b, target, mode, advance)
        except TargetError as exc:
            report.write_errors[b.start] = str(exc)
            advance(b.count - (done - start_done))
    report.after = verify(image, target, todo)
    if reset and todo and report.ok:
        reset_drive(target)
        report.reset = True
    return report
