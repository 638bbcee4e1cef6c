#!/usr/bin/env python3
"""Guest instructions executed, per symbol, from a qemu-user log.

Reads the log of `qemu-aarch64 -d in_asm,exec,nochain -D LOG PROGRAM ...`
(or qemu-x86_64) from a file or a FIFO and prints one line per symbol:
instructions executed, then the symbol name as qemu printed it (mangled).

How: `in_asm` prints each translation block (TB) once, when it is translated,
as "IN: symbol" and one line per guest instruction; `exec` with `nochain`
prints "Trace N: HOST [x/GUEST_PC/flags/cflags] symbol" each time a TB runs.
A TB's instructions times the times it ran, summed per symbol, is the
instruction count (a TB left early by a signal or a fault would be counted
whole; a decode has none). Code qemu has no symbols for (shared libraries
loaded by the dynamic linker) is summed under "?".

With --stages FILE, also splits the instructions by stage, in the order
they ran: FILE has lines "LABEL OFFSET", OFFSET the hex address of a
function in the program's ELF file (nm; a label may have several), and
one line "_start OFFSET" that gives the load base. Every TB run after the entry of a stage's function and
before the entry of the next listed function counts for that stage; before
the first entry, for "(start)". Printed as "stage LABEL COUNT" lines.

Only the Python standard library: runs with any python3.
"""
import sys


def main() -> int:
    args = sys.argv[1:]
    offsets = []    # (stage label, offset of its function in the ELF file)
    start = None
    if len(args) == 3 and args[1] == "--stages":
        with open(args[2]) as stages_file:
            for entry in stages_file:
                if entry.strip():
                    label, offset = entry.split()
                    if label == "_start":
                        start = int(offset, 16)
                    else:
                        offsets.append((label, int(offset, 16)))
        if start is None:
            print("count_tb_instructions.py: the stages file has no _start line", file=sys.stderr)
            return 2
        del args[1:]
    if len(args) != 1:
        print("usage: count_tb_instructions.py QEMU_LOG [--stages FILE]", file=sys.stderr)
        return 2
    entries = {}    # guest pc of a stage function's entry -> stage label
    stage = "(start)"
    by_stage = {}   # stage label -> instructions
    size = {}       # guest pc -> instructions in the TB last translated there
    name = {}       # guest pc -> symbol
    runs = {}       # guest pc -> times run since its size was last set
    credit = {}     # symbol -> instructions
    block_pc = None
    block_name = ""
    block_size = 0

    def flush(pc: int) -> None:
        n = runs.pop(pc, 0)
        if n:
            credit[name[pc]] = credit.get(name[pc], 0) + n * size[pc]

    with open(args[0], "r", errors="replace") as log:
        in_block = False
        for line in log:
            if line.startswith("Trace "):
                # Trace 0: 0x7f263e800100 [0000000001009331/000000550283ce40/00000001/00000200] sym
                lb = line.index("[")
                pc = int(line[lb + 1:line.index("]", lb)].split("/")[1], 16)
                runs[pc] = runs.get(pc, 0) + 1
                if offsets:
                    if pc in entries:
                        stage = entries[pc]
                    by_stage[stage] = by_stage.get(stage, 0) + size.get(pc, 0)
            elif in_block:
                if line.startswith("0x"):
                    if block_size == 0:
                        block_pc = int(line[:line.index(":")], 16)
                    block_size += 1
                else:
                    in_block = False
                    if block_size:
                        if block_pc in size:
                            flush(block_pc)
                        size[block_pc] = block_size
                        name[block_pc] = block_name or "?"
                        if block_name == "_start" and offsets and not entries:
                            base = block_pc - start
                            entries = {base + offset: label for label, offset in offsets}
            elif line.startswith("IN:"):
                in_block = True
                block_name = line[3:].strip()
                block_size = 0
    for pc in list(runs):
        if pc in size:
            flush(pc)
    for symbol, count in sorted(credit.items(), key=lambda item: -item[1]):
        print(count, symbol)
    for label, count in by_stage.items():
        print("stage", label, count)
    return 0


if __name__ == "__main__":
    sys.exit(main())
