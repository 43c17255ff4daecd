"""Ports that come up on first flash: what can be checked here without the boards.

STM32H743 (built with arm-none-eabi-gcc): Reset_Handler's first instruction
sets SP to _estack; the image carries the bounded waits' poll limits
(``h7_wait_polls``); port_init runs in unicorn against simulated RCC, PWR,
FLASH, GPIO, USART3 and core (SCB/MPU/DWT) registers: the MPU background
region before the caches, ST's clock order, the console's first lines, a PLL
that never locks (ERROR line, then blink code 6 after exactly the table's
polls), an exception before the console (blink code 9, nothing sent).

TMS320F28377S (TI's cl2000 is not installable here, the image cannot be
linked): the words placed in section ``codestart`` are counted from
codestart.c's instructions and must fit region BEGIN of f28377s.cmd; the
command file's regions and the stack size are checked against the memory
map; port_init's sequences run on the host against a simulated register file
(c28x_sim.c): TI's flash, crystal, PLL and SCI order and delays, and the
failure reports (pump, PLL dead or slipping, crystal dead).
"""
from __future__ import annotations

import re
import struct
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from codegen.hostbuild import STRICT_CFLAGS
from codegen.stages import firmware as firmware

from fw_support import ROOT, example, needs_arm, require_tool

HERE = Path(__file__).resolve().parent
C28X = ROOT / "firmware" / "ports" / "tms320f28377"
H7 = ROOT / "firmware" / "ports" / "stm32h743"


# ------------------------------------------------------------------ TMS320F28377S: codestart vs BEGIN

#: 16-bit words of the C28x instructions a start-up branch may use (SPRU430, C28x instruction set)
C28X_WORDS = {"LB": 2, "LCR": 2, "SETC": 1, "CLRC": 1, "EALLOW": 1, "EDIS": 1, "MOVZ": 1, "NOP": 1,
              "ESTOP0": 1, "MOVL": 2}


def c28x_instruction_words(line: str) -> int:
    """Words of one C28x instruction (MOV with a 16-bit immediate is 2 words, other MOVs 1)."""
    mnemonic = line.split()[0].upper()
    if mnemonic == "MOV":
        return 2 if "#" in line else 1
    if mnemonic not in C28X_WORDS:
        pytest.fail(f"codestart.c: instruction {mnemonic!r} has no word count here: add it to C28X_WORDS")
    return C28X_WORDS[mnemonic]


def section_words(asm: list[str]) -> tuple[dict[str, int], dict[str, list[str]]]:
    """Words per section and each section's labels, in order, from asm source lines."""
    words: dict[str, int] = {}
    labels: dict[str, list[str]] = {}
    section = ".text"
    for raw in asm:
        line = raw.split(";")[0].strip()
        if not line:
            continue
        if line.endswith(":"):
            labels.setdefault(section, []).append(line[:-1])
            continue
        if line.startswith("."):
            m = re.match(r'\.sect\s+"([^"]+)"', line)
            if m:
                section = m.group(1)
            elif line.split()[0] in (".text", ".data"):
                section = line.split()[0]
            continue
        words[section] = words.get(section, 0) + c28x_instruction_words(line)
    return words, labels


def codestart_asm(source: str) -> list[str]:
    """The asm lines of codestart.c's cl2000 branch (one __asm statement each)."""
    ti = source.split("#if defined(__TI_COMPILER_VERSION__)", 1)[1].split("#else", 1)[0]
    return [s.replace('\\"', '"') for s in re.findall(r'__asm\("((?:\\.|[^"\\])*)"\)', ti)]


def memory_regions(cmd: str) -> dict[str, tuple[int, int]]:
    """MEMORY regions of a TI linker command file: name -> (origin, length) in words."""
    block = re.search(r"MEMORY\s*\{(.*?)\}", re.sub(r"/\*.*?\*/", "", cmd, flags=re.S), re.S)
    assert block, "no MEMORY block"
    return {m.group(1): (int(m.group(2), 16), int(m.group(3), 16))
            for m in re.finditer(r"(\w+)\s*:\s*origin\s*=\s*0x([0-9A-Fa-f]+)\s*,\s*length\s*=\s*0x([0-9A-Fa-f]+)",
                                 block.group(1))}


def section_placements(cmd: str) -> dict[str, list[str]]:
    """SECTIONS of the command file: output section -> the regions it names."""
    block = re.search(r"SECTIONS\s*\{(.*)\}", re.sub(r"/\*.*?\*/", "", cmd, flags=re.S), re.S)
    assert block, "no SECTIONS block"
    out = {}
    for line in block.group(1).splitlines():
        m = re.match(r"\s*(\S+)\s*:(.*)$", line)
        if m:
            out[m.group(1)] = re.findall(r"(?:>|LOAD\s*=|RUN\s*=)\s*(\w+)", m.group(2))
    return out


def test_f28377s_codestart_fits_begin():
    cmd = (C28X / "f28377s.cmd").read_text()
    regions = memory_regions(cmd)
    placed = section_placements(cmd)
    assert placed["codestart"] == ["BEGIN"]
    assert regions["BEGIN"][0] == 0x080000, "BEGIN must be the boot-to-flash entry address"
    words, labels = section_words(codestart_asm((C28X / "codestart.c").read_text()))
    assert words.get("codestart", 0) <= regions["BEGIN"][1], (
        f"section codestart holds {words.get('codestart', 0)} words, region BEGIN {regions['BEGIN'][1]}")
    assert words["codestart"] == 2 and labels["codestart"][0] == "code_start"
    assert words.get(".text", 0) >= 6  # the watchdog disable went to the code the branch reaches
    assert "--entry_point=code_start" in (C28X / "build.sh").read_text()


def test_codestart_count_catches_the_old_layout():
    """The count is not vacuous: the watchdog disable inside codestart is 7 words (BEGIN has 2)."""
    old = ['.sect "codestart"', "code_start:", "EALLOW", "MOVZ DP, #7029h >> 6", "MOV @7029h, #0068h", "EDIS",
           "LB _c_int00"]
    assert section_words(old)[0]["codestart"] == 7


#: F28377S memories (data sheet SPRS881 memory map), in 16-bit words: start, end (exclusive)
F28377S_MEMORY = {"M0": (0x000000, 0x000400), "M1": (0x000400, 0x000800), "LS0-5": (0x008000, 0x00B000),
                  "D0-1": (0x00B000, 0x00C000), "GS0-15": (0x00C000, 0x01C000), "flash": (0x080000, 0x0C0000),
                  "boot ROM": (0x3F8000, 0x400000)}


def test_f28377s_regions_and_stack_fit_the_memory_map():
    cmd = (C28X / "f28377s.cmd").read_text()
    regions = memory_regions(cmd)
    spans = sorted((o, o + n, name) for name, (o, n) in regions.items())
    for (_, end, a), (start, _, b) in zip(spans, spans[1:], strict=False):
        assert end <= start, f"regions {a} and {b} overlap"
    for name, (origin, length) in regions.items():
        assert any(lo <= origin and origin + length <= hi for lo, hi in F28377S_MEMORY.values()), name
    for section, names in section_placements(cmd).items():
        assert names and all(n in regions for n in names), (section, names)
    assert regions["FLASH"][0] == regions["BEGIN"][0] + regions["BEGIN"][1]
    stack = re.search(r"--stack_size=0x([0-9A-Fa-f]+)", (C28X / "build.sh").read_text())
    assert stack and int(stack.group(1), 16) <= regions[section_placements(cmd)[".stack"][0]][1]


# ------------------------------------------------------------------ TMS320F28377S: port_init on the host

@pytest.fixture(scope="module")
def c28x_sim(tmp_path_factory) -> Path:
    """port_init of the tms320f28377 port linked with the simulated register file (c28x_sim.c)."""
    m, t = example("spmsm", "s3")
    out = tmp_path_factory.mktemp("c28x-sim")
    firmware.write_firmware_project(m, t, "tms320f28377", out, 100, n_bench=0)
    incs = [f"-I{out / d}" for d in ("gen", "firmware/runtime", "firmware/ports/tms320f28377")]
    flags = [*STRICT_CFLAGS, "-DMPC_C28X_TYPE_MODEL", "-DMPC_C28X_HOST_SIM", "--param=min-pagesize=0", *incs]
    model = ["-include", str(HERE / "c28x_type_model.h")]
    objs = []
    for src in (out / "firmware/ports/tms320f28377/board.c", out / "firmware/runtime/console.c", HERE / "c28x_sim.c"):
        obj = out / (src.stem + ".o")
        r = subprocess.run(["gcc", *flags, *(model if src.parent != HERE else []), "-c", str(src), "-o", str(obj)],
                           capture_output=True, text=True)
        assert r.returncode == 0, f"{src.name}:\n{r.stderr}"
        objs.append(str(obj))
    exe = out / "c28x_sim"
    subprocess.run(["gcc", *objs, "-o", str(exe)], check=True)
    return exe


@dataclass
class C28xRun:
    """One simulated port_init: register accesses (address, value after, NOP cycles so far), events."""

    log: list[tuple[str, int, int, int]] = field(default_factory=list)  # ("R", addr, value, cycles) / ("A"|"D", ...)
    tx: str = ""

    def values(self, addr: int) -> list[int]:
        return [v for kind, a, v, _ in self.log if kind == "R" and a == addr]

    def first(self, addr: int, pred=lambda v: True) -> int:
        """Index of the first access of ``addr`` whose value satisfies ``pred`` (-1: none)."""
        return next((i for i, (k, a, v, _) in enumerate(self.log) if k == "R" and a == addr and pred(v)), -1)


def run_c28x(exe: Path, *scenario: str) -> C28xRun:
    r = subprocess.run([str(exe), *scenario], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr
    run = C28xRun()
    for line in r.stdout.splitlines():
        p = line.split()
        if p[0] == "R":
            run.log.append(("R", int(p[1], 16), int(p[2], 16), int(p[3])))
        elif p[0] == "E":
            run.log.append((p[1], 0, 0, int(p[2])))
        elif p[0] == "TX":
            run.tx = bytes.fromhex(p[1] if len(p) > 1 else "").decode()
    return run


CLKSRCCTL1, SYSPLLCTL1, SYSPLLMULT, SYSCLKDIVSEL, LOSPCP, MCDCR = 0x5D208, 0x5D20E, 0x5D214, 0x5D222, 0x5D22C, 0x5D22E
FRDCNTL, FRD_INTF_CTRL, FBAC, PUMPREQUEST = 0x5F800, 0x5F980, 0x5F81E, 0x50024
SCICTL1, SCILBAUD, SCIFFTX = 0x7201, 0x7203, 0x720A
PROTECTED = ((0x5D000, 0x5E000), (0x5F800, 0x5FC00), (0x7C00, 0x7D00), (0x50024, 0x50026))


def test_c28x_port_init_follows_ti_order(c28x_sim):
    run = run_c28x(c28x_sim)
    assert "osc=xtal" in run.tx and "ERROR" not in run.tx and run.tx.endswith("EXIT code=0\r\n")
    # every write to an EALLOW-protected register lies between EALLOW and EDIS
    allowed = False
    for kind, addr, _, _ in run.log:
        allowed = True if kind == "A" else False if kind == "D" else allowed
        if kind == "R" and any(lo <= addr < hi for lo, hi in PROTECTED):
            assert allowed, f"{addr:#x} accessed outside EALLOW"
    # flash: pump claimed first, VREADST 0x14, cache/prefetch off while RWAIT changes, then on, pipeline flush
    claim = run.first(PUMPREQUEST, lambda v: v == 2)
    assert 0 <= claim < run.first(FBAC, lambda v: v & 0xFF == 0x14)
    off = run.first(FRD_INTF_CTRL, lambda v: v & 3 == 0)
    rwait = run.first(FRDCNTL, lambda v: (v >> 8) & 0xF == 3)
    assert 0 <= off < rwait < run.first(FRD_INTF_CTRL, lambda v: v & 3 == 3)
    edis = next(i for i, e in enumerate(run.log) if e[0] == "D")
    assert run.log[edis + 1][0] == "A" and run.log[edis + 1][3] - run.log[edis][3] >= 8  # RPT #7 || NOP
    # crystal: on, >= 1 ms at 10 MHz, selected, missing clock detect read after it
    xon = run.first(CLKSRCCTL1, lambda v: not v & 0x10)
    sel = run.first(CLKSRCCTL1, lambda v: v & 3 == 1)
    assert 0 <= xon < sel and run.log[sel][3] - run.log[xon][3] >= 10_000 and run.first(MCDCR) > sel
    # PLL: bypassed and /1 first, locked five times (PLLEN off >= 60 cycles before each), /4, PLLCLKEN, /2
    bypass = run.first(SYSPLLCTL1, lambda v: not v & 2)
    assert 0 <= bypass < run.first(SYSCLKDIVSEL, lambda v: v == 0) < sel
    mults = [i for i, e in enumerate(run.log) if e[0] == "R" and e[1] == SYSPLLMULT]
    assert len(mults) == 5 and all(run.log[i][2] == 40 for i in mults)
    for i in mults:
        pllen_off = max(j for j in range(i) if run.log[j][1] == SYSPLLCTL1 and not run.log[j][2] & 1)
        assert run.log[i][3] - run.log[pllen_off][3] >= 60
    clken = run.first(SYSPLLCTL1, lambda v: v & 2)
    div4 = run.first(SYSCLKDIVSEL, lambda v: v == 2)
    div2 = run.first(SYSCLKDIVSEL, lambda v: v == 1)
    assert mults[-1] < div4 < clken < div2 and run.log[div2][3] - run.log[clken][3] >= 200
    # SCI: held in reset, SCIFFTX = 0x8000 (SCIRST set, FIFO off), 115200 from 50 MHz (BRR 53), released
    assert run.values(SCIFFTX) == [0x8000] and run.values(SCILBAUD) == [53]
    assert run.first(SCIFFTX) < run.first(SCICTL1, lambda v: v == 0x23)


@pytest.mark.parametrize("scenario, stage", [(("pll-dead",), "pll-lock"), (("pll-slip",), "pll-lock"),
                                             (("pump-deny",), "flash-pump-semaphore"),
                                             (("xtal-dead", "pll-dead"), "pll-lock")])
def test_c28x_failures_reach_the_console(c28x_sim, scenario, stage):
    run = run_c28x(c28x_sim, *scenario)
    assert f"ERROR port_init board=tms320f28377 stage={stage}" in run.tx and run.tx.endswith("EXIT code=4\r\n")
    if stage == "pll-lock":
        # PLL off, SYSCLK = OSCCLK: LSPCLK /1 = 10 MHz, 115200 baud with BRR 10; bounded: at 10 MHz,
        # the crystal's waits (1 ms + 5 x 2 ms + 1 ms) and five locks of 10 ms are at most 62 ms
        assert run.first(SYSPLLCTL1, lambda v: v & 2) == -1 and run.values(LOSPCP)[-1] == 0
        assert run.values(SCILBAUD) == [10] and run.log[-1][3] <= 620_000 + 1_000
    else:
        assert run.values(FRDCNTL) == []  # never touched: reset wait states (the most)


def test_c28x_dead_crystal_falls_back_to_intosc2(c28x_sim):
    run = run_c28x(c28x_sim, "xtal-dead")
    assert "osc=intosc2" in run.tx and "ERROR" not in run.tx and run.tx.endswith("EXIT code=0\r\n")
    assert sum(1 for v in run.values(MCDCR) if v & 2) == 5  # 4 retries, then the clear after INTOSC2
    assert run.values(CLKSRCCTL1)[-1] & 0x13 == 0x10  # INTOSC2 selected, crystal off


# ------------------------------------------------------------------ STM32H743: the built image

PWR_CSR1, PWR_D3CR, RCC_CR, RCC_CFGR = 0x58024804, 0x58024818, 0x58024400, 0x58024410
RCC_PLL1DIVR, FLASH_ACR, GPIOB_BSRR = 0x58024430, 0x52002000, 0x58020418
USART3_BRR, USART3_ISR, USART3_TDR = 0x4000480C, 0x4000481C, 0x40004828
SCB_CCR, MPU_CTRL, MPU_RBAR, MPU_RASR, DWT_CYCCNT = 0xE000ED14, 0xE000ED94, 0xE000ED9C, 0xE000EDA0, 0xE0001004
W_PLL1_LOCK, W_HSE = 5, 8


@pytest.fixture(scope="module")
def h7_image(tmp_path_factory) -> Path:
    require_tool("arm-none-eabi-gcc", "gcc-arm-none-eabi libnewlib-arm-none-eabi")
    m, t = example("spmsm", "s3")
    out = tmp_path_factory.mktemp("h7")
    firmware.write_firmware_project(m, t, "stm32h743", out, 100, n_bench=10)
    res = firmware.build_firmware(out, "stm32h743")
    assert "warning" not in res.log.lower(), res.log
    assert res.stack_path[:2] == ["Reset_Handler(0)", "cm7_reset(8)"], res.stack_path  # stackdepth.sh's asm edge
    return res.image


def symbols(elf: Path) -> dict[str, tuple[int, int]]:
    """Every symbol of the image: name -> (address, size)."""
    nm = subprocess.run(["arm-none-eabi-nm", "-S", str(elf)], capture_output=True, text=True, check=True).stdout
    out = {}
    for line in nm.splitlines():
        p = line.split()
        if len(p) == 4:
            out[p[3]] = (int(p[0], 16), int(p[1], 16))
        elif len(p) == 3:
            out[p[2]] = (int(p[0], 16), 0)
    return out


def load_images(elf: Path) -> list[tuple[int, bytes]]:
    """The PT_LOAD segments of a little-endian ELF32 image at their load (physical) addresses."""
    data = elf.read_bytes()
    phoff, phentsize, phnum = struct.unpack_from("<I", data, 28)[0], *struct.unpack_from("<HH", data, 42)
    out = []
    for i in range(phnum):
        p_type, offset, _vaddr, paddr, filesz = struct.unpack_from("<5I", data, phoff + i * phentsize)
        if p_type == 1 and filesz:
            out.append((paddr, data[offset:offset + filesz]))
    return out


class H7Sim:
    """The stm32h743 image in unicorn with simulated peripherals (only what port_init needs)."""

    def __init__(self, elf: Path, *, hse: bool = True, pll_locks: bool = True, polls: dict[int, int] | None = None):
        import unicorn
        from unicorn import arm_const

        self.uc_mod, self.arm = unicorn, arm_const
        self.sym = symbols(elf)
        self.hse, self.pll_locks = hse, pll_locks
        self.regs: dict[int, int] = {}
        self.log: list[tuple[str, int, int]] = []
        self.tx = bytearray()
        self.cyccnt = 0
        self.led_on = 0  # LD3 (PB14) set writes so far
        uc = unicorn.Uc(unicorn.UC_ARCH_ARM, unicorn.UC_MODE_THUMB | unicorn.UC_MODE_MCLASS)
        uc.ctl_set_cpu_model(arm_const.UC_CPU_ARM_CORTEX_M7)
        for base, size in ((0x00000000, 64 << 10), (0x08000000, 2 << 20), (0x20000000, 128 << 10)):
            uc.mem_map(base, size)
        for addr, data in load_images(elf):  # at their load addresses: Reset_Handler copies them
            uc.mem_write(addr, data)
        for base, size in ((0x40004000, 0x1000), (0x52002000, 0x1000), (0x58020000, 0x1000),
                           (0x58024000, 0x1000), (0xE0000000, 0x100000)):
            uc.mmio_map(base, size, self._read, base, self._write, base)
        table = self.sym["h7_wait_polls"][0]
        self.polls = list(memoryview(bytes(uc.mem_read(table, self.sym["h7_wait_polls"][1]))).cast("I"))
        for index, value in (polls or {}).items():  # shorter waits where the test waits out a timeout
            uc.mem_write(table + 4 * index, value.to_bytes(4, "little"))
        self.uc = uc

    def _read(self, _uc, offset: int, _size: int, base: int) -> int:
        addr = base + offset
        v = self.regs.get(addr, 0)
        if addr == PWR_CSR1:
            v |= 1 << 13  # ACTVOSRDY
        elif addr == PWR_D3CR:
            v |= 1 << 13  # VOSRDY
        elif addr == RCC_CR:
            v |= (4 if v & 1 else 0) | (1 << 17 if v & (1 << 16) and self.hse else 0)
            v |= 1 << 25 if v & (1 << 24) and self.pll_locks else 0
        elif addr == RCC_CFGR:
            v = (v & ~0x38) | ((v & 7) << 3)  # SWS follows SW
        elif addr == USART3_ISR:
            v = 0xC0  # TXE, TC
        elif addr == DWT_CYCCNT:
            self.cyccnt = (self.cyccnt + 1_000_000) & 0xFFFFFFFF
            v = self.cyccnt
        self.log.append(("r", addr, v))
        return v

    def _write(self, _uc, offset: int, _size: int, value: int, base: int) -> None:
        addr = base + offset
        self.regs[addr] = value
        self.log.append(("w", addr, value))
        if addr == USART3_TDR:
            self.tx.append(value & 0xFF)
        elif addr == GPIOB_BSRR and value == 1 << 14:
            self.led_on += 1

    def run(self, entry: str, *, sp: int = 0, r0: int = 0, lines: int = 0, flashes: int = 0,
            count: int = 20_000_000) -> int:
        """Run from ``entry`` until h7_halt (its r0, the blink code, is returned; with ``flashes``: until
        that many LED flashes) or ``lines`` console lines (returns -1)."""
        uc, a = self.uc, self.arm
        halt = self.sym["h7_halt"][0]
        self.code = -1

        def block(_uc, addr, _size, _u):
            if addr == halt and self.code < 0:
                self.code = uc.reg_read(a.UC_ARM_REG_R0)
                if not flashes:
                    uc.emu_stop()
            if (lines and self.tx.count(b"\n") >= lines) or (flashes and self.led_on >= flashes):
                uc.emu_stop()

        hook = uc.hook_add(self.uc_mod.UC_HOOK_BLOCK, block)
        uc.reg_write(a.UC_ARM_REG_SP, sp)
        uc.reg_write(a.UC_ARM_REG_R0, r0)
        try:
            uc.emu_start(self.sym[entry][0] | 1, 0xFFFFFFFF, count=count)
        finally:
            uc.hook_del(hook)
        return self.code

    def writes(self, addr: int) -> list[tuple[int, int]]:
        return [(i, v) for i, (k, a, v) in enumerate(self.log) if k == "w" and a == addr]


@needs_arm
def test_h7_reset_handler_sets_sp_first(h7_image):
    sim = H7Sim(h7_image)
    sim.uc.emu_start(sim.sym["Reset_Handler"][0] | 1, 0xFFFFFFFF, count=1)  # one instruction, from SP = 0
    assert sim.uc.reg_read(sim.arm.UC_ARM_REG_SP) == sim.sym["_estack"][0] == 0x20020000


@needs_arm
def test_h7_waits_are_bounded_in_the_image(h7_image):
    sim = H7Sim(h7_image)
    assert len(sim.polls) == 9 and all(0 < p < 0x10000000 for p in sim.polls), sim.polls
    # the clock code waits only through h7_wait (no other loop in it)
    src = re.sub(r"/\*.*?\*/", "", (H7 / "board.c").read_text(), flags=re.S)
    for fn in ("power_init", "clock_defaults", "clock_init"):
        body = re.search(rf"^static void {fn}\(void\)\n\{{(.*?)^\}}", src, re.M | re.S)
        assert body and not re.search(r"\b(while|for)\b", body.group(1)), fn
    assert "0xFFFFFFFFu" not in src


@needs_arm
def test_h7_port_init_in_order(h7_image):
    sim = H7Sim(h7_image)
    assert sim.run("Reset_Handler", lines=2) == -1  # from SP = 0: Reset_Handler's SP is what runs
    text = sim.tx.decode()
    assert text.startswith("HELLO mpcgen board=stm32h743") and "pll1_src=hse-bypass-8MHz" in text
    assert "mpu=background" in text
    # ST's MPU_Config before the caches: region 0 = 4 GB, no access, XN, SRD 0x87; PRIVDEFENA | ENABLE
    assert [v for _, v in sim.writes(MPU_RASR)] == [0x1004873F] and [v for _, v in sim.writes(MPU_RBAR)] == [0]
    mpu_on = next(i for i, v in sim.writes(MPU_CTRL) if v == 5)
    caches_on = [i for i, v in sim.writes(SCB_CCR) if v & (3 << 16)]
    assert caches_on and min(caches_on) > mpu_on
    # HSEBYP written before HSEON; PLL1 dividers before PLL1ON; flash latency before the switch to PLL1
    cr = sim.writes(RCC_CR)
    byp = next(i for i, v in cr if v & (1 << 18))
    assert all(not v & (1 << 16) for i, v in cr if i <= byp) and any(v & (1 << 16) for i, v in cr if i > byp)
    pll_on = next(i for i, v in cr if v & (1 << 24))
    assert sim.writes(RCC_PLL1DIVR)[-1][0] < pll_on < sim.writes(FLASH_ACR)[-1][0] < sim.writes(RCC_CFGR)[-1][0]
    assert sim.writes(RCC_CFGR)[-1][1] & 7 == 3 and sim.writes(USART3_BRR)[-1][1] == 868  # 100 MHz / 115200


@needs_arm
def test_h7_dead_pll_is_reported_and_blinks(h7_image):
    sim = H7Sim(h7_image, pll_locks=False)
    assert sim.run("Reset_Handler", flashes=7) == W_PLL1_LOCK + 1
    assert sim.tx.decode() == ("ERROR port_init board=stm32h743 stage=pll1-lock sysclk=hsi-64MHz blink=6\r\n"
                               "EXIT code=4\r\n")
    assert sim.writes(USART3_BRR)[-1][1] == 556  # the console at the 64 MHz HSI kernel clock
    pll_on = next(i for i, v in sim.writes(RCC_CR) if v & (1 << 24))
    polls = sum(1 for k, a, _ in sim.log[pll_on:] if k == "r" and a == RCC_CR)
    assert polls == sim.polls[W_PLL1_LOCK]  # bounded: exactly the table's limit, then the report
    # six flashes, a pause, the next round: DWT reads (time) before each LED-on write
    gaps, reads = [], 0
    for kind, addr, value in sim.log[pll_on:]:
        reads += kind == "r" and addr == DWT_CYCCNT
        if kind == "w" and addr == GPIOB_BSRR and value == 1 << 14:
            gaps.append(reads)
            reads = 0
    assert len(gaps) == sim.led_on == 7 and gaps[6] > 3 * max(gaps[1:6]), gaps


@needs_arm
def test_h7_missing_hse_falls_back_to_hsi(h7_image):
    sim = H7Sim(h7_image, hse=False, polls={W_HSE: 1000})
    assert sim.run("Reset_Handler", lines=2) == -1
    assert "pll1_src=hsi-64MHz" in sim.tx.decode()


@needs_arm
def test_h7_fault_before_console_blinks(h7_image):
    sim = H7Sim(h7_image)
    assert sim.run("cm7_fault", sp=0x20020000, r0=3) == 9 and sim.tx == b""
    sim = H7Sim(h7_image)
    sim.uc.mem_write(sim.sym["console_ready"][0], (1).to_bytes(2, "little"))
    assert sim.run("cm7_fault", sp=0x20020000, r0=3) == 9 and sim.tx.decode() == "FAULT vector=3\r\n"


def test_h7_mpu_before_caches_in_source():
    body = re.search(r"^void port_init\(void\)\n\{(.*?)^\}", (H7 / "board.c").read_text(), re.M | re.S)
    assert body
    calls = re.findall(r"(\w+)\(", body.group(1))
    assert calls.index("mpu_init") < calls.index("caches_init") < calls.index("clock_init")
