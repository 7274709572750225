"""Download plans: the CoE SDO writes that program a ``.sw`` image into the drive EEPROM (manual §17.4).

Per block:
  1. 2064h := ``start << 16 | 0x0008`` (EEPROM, 16-bit data, auto-increment) or ``| 0x0009`` (32-bit);
  2. 2065h := one data word per write (16-bit mode), or two words per write, the lower address in the low
     half (32-bit mode, §17.4.1: 0x1234 @0x5E06, 0x5678 @0x5E07 -> 0x56781234). A block with an odd word
     count ends with 2064h := ``last << 16 | 0x0008`` and one 16-bit write, so nothing is written past the
     end of the block (padding with an extra word would overwrite the next EEPROM word);
  3. 2069h := ``end << 16 | start`` makes the drive sum the block into 206Ah, which must equal the block
     checksum (the comment of the command says which value).
Then 2080h := 1 resets the drive so it loads the new setup; the drive answers that write by resetting,
not with an SDO reply (``expect_reply=False``).
"""

from __future__ import annotations

from ecattool.startup.model import StartupCommand, StartupList
from ecattool.sw.image import Block, SwImage

OBJ_CONFIG = 0x2064
OBJ_WRITE = 0x2065
OBJ_READ = 0x2066
OBJ_WRITE_AT = 0x2067
OBJ_CHECKSUM_RANGE = 0x2069
OBJ_CHECKSUM = 0x206A
OBJ_RESET = 0x2080
OBJ_LOCK = 0x2091

#: 2064h low bits: bits 3..2 = 10 (EEPROM), bit 7 = 0 (auto-increment), bit 0 = data width
CFG_EEPROM_16 = 0x0008
CFG_EEPROM_32 = 0x0009

MODES = (16, 32)


def config_value(address: int, mode: int = 16) -> int:
    """The 2064h value selecting EEPROM ``address`` with auto-increment (§17.4: 0x5638 -> 0x56380008)."""
    if mode not in MODES:
        raise ValueError(f"mode must be 16 or 32, not {mode}")
    return (address << 16) | (CFG_EEPROM_32 if mode == 32 else CFG_EEPROM_16)


def _u32(index: int, value: int, comment: str, verify: bool = True) -> StartupCommand:
    # EEPROM programming is written once (kind "once"), never as a startup write a master repeats
    return StartupCommand("PS", index, 0, value.to_bytes(4, "little"), comment=comment, type_name="UDINT",
                          value=value, verify=verify, once=True)


def block_commands(block: Block, mode: int = 16) -> list[StartupCommand]:
    """2064h/2065h writes that program one block (no checksum request). A one-word block in 32-bit mode is
    written in 16-bit mode at once: selecting 32-bit first would only be undone by the 16-bit selection the
    odd last word needs (a second 2064h write for every one-word block)."""
    words = block.words
    if mode == 32 and len(words) == 1:
        mode = 16
    cmds = [_u32(OBJ_CONFIG, config_value(block.start, mode),
                 f"EEPROM 0x{block.start:04X}, {mode}-bit, auto-increment ({block.count} words)")]
    if mode == 16:
        cmds += [_u32(OBJ_WRITE, w, f"@0x{block.start + i:04X}", verify=False) for i, w in enumerate(words)]
        return cmds
    pairs = len(words) // 2
    for k in range(pairs):
        lo, hi = words[2 * k], words[2 * k + 1]
        cmds.append(_u32(OBJ_WRITE, (hi << 16) | lo, f"@0x{block.start + 2 * k:04X}..0x{block.start + 2 * k + 1:04X}",
                         verify=False))
    if len(words) % 2:
        last = block.end
        cmds.append(_u32(OBJ_CONFIG, config_value(last, 16), f"EEPROM 0x{last:04X}, 16-bit for the odd last word"))
        cmds.append(_u32(OBJ_WRITE, words[-1], f"@0x{last:04X}", verify=False))
    return cmds


def checksum_command(block: Block) -> StartupCommand:
    return _u32(OBJ_CHECKSUM_RANGE, block.checksum_request,
                f"checksum 0x{block.start:04X}..0x{block.end:04X}: 206Ah must read 0x{block.checksum:04X}")


def reset_command() -> StartupCommand:
    return StartupCommand("PS", OBJ_RESET, 0, (1).to_bytes(2, "little"), comment="reset the drive to load the new setup (no SDO reply)",
                          type_name="UINT", value=1, expect_reply=False, verify=False, once=True)


def download_plan(image: SwImage, mode: int = 16, blocks: list[Block] | None = None, reset: bool = True,
                  name: str = "") -> StartupList:
    """The SDO writes that program ``image`` (or only ``blocks`` of it), check each block, then reset."""
    if mode not in MODES:
        raise ValueError(f"mode must be 16 or 32, not {mode}")
    plan = StartupList(name=name or (image.source or ""))
    for b in image.blocks if blocks is None else blocks:
        plan.extend(block_commands(b, mode))
        plan.commands.append(checksum_command(b))
    if reset:
        plan.commands.append(reset_command())
    return plan


def eeprom_writes(plan: StartupList | list[StartupCommand]) -> dict[int, int]:
    """Replay the 2064h/2065h writes of a plan the way the drive applies them: address -> word.

    Used by the tests as an independent check that a plan writes exactly the image (and nothing past it).
    """
    memory: dict[int, int] = {}
    address = 0
    width = 16
    for c in plan:
        v = c.int_value
        if c.index == OBJ_CONFIG:
            address, width = v >> 16, 32 if v & 1 else 16
        elif c.index == OBJ_WRITE:
            memory[address] = v & 0xFFFF
            if width == 32:
                memory[address + 1] = v >> 16
                address += 2
            else:
                address += 1
    return memory
