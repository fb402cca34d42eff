#!/usr/bin/env python3
"""A real Modbus RTU master (pymodbus) for tools/tests/vnano_modbus.rs.

    modbus_master.py PORT functions        every function and exception of SPEC 13
    modbus_master.py PORT read TABLE A N   print N values of TABLE (co, di, hr, ir) from A
    modbus_master.py PORT coil A 0|1       write single coil A
    modbus_master.py PORT reg A V          write single register A
    modbus_master.py PORT wire             bad CRC, another address, a broadcast
    modbus_master.py PORT poll N           N reads of coils in a row, all answered
    modbus_master.py PORT slave S ...      the same commands, to slave S
    modbus_master.py PORT bus N            slaves 1..N on one line, and a broadcast
    modbus_master.py PORT windows          SPEC 17: the snapshot (64..103) and the program
                                           (256..383); prints them, checks exception 02
    modbus_master.py PORT hold             SPEC 18 on a program whose Y0..Y7 count its scans
                                           (tests/data/scan_counter.utl): hold, steps,
                                           exception 03, release, the 10 s lease

Prints one line per check or value; exits 1 with the reason when a check fails.
"""

import sys
import time

from pymodbus.client import ModbusSerialClient
from pymodbus.pdu import ExceptionResponse

SLAVE = 1


def fail(why):
    print("FAIL:", why)
    sys.exit(1)


def ok(resp, what):
    if resp.isError():
        fail(f"{what}: {resp}")
    return resp


def exception(resp, code, what):
    if not isinstance(resp, ExceptionResponse) or resp.exception_code != code:
        fail(f"{what}: expected exception {code}, got {resp}")
    print(f"{what}: exception {code}")


def crc16(data):
    crc = 0xFFFF
    for b in data:
        crc ^= b
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
    return crc


def raw(c, pdu):
    """A request pymodbus itself refuses to build; the reply's bytes."""
    time.sleep(0.05)  # the silence a master leaves before a frame
    frame = bytes([SLAVE]) + bytes(pdu)
    frame += crc16(frame).to_bytes(2, "little")
    c.socket.reset_input_buffer()
    c.socket.write(frame)
    time.sleep(0.3)
    return c.socket.read(c.socket.in_waiting or 1)


def functions(c):
    # 03 / 06 / 16: timer preset T3 = 42 (0..255), counter presets, set-points (0..1023).
    ok(c.write_register(3, 42, slave=SLAVE), "06 T3")
    ok(c.write_registers(16, [1000, 65535], slave=SLAVE), "16 C0 C1")
    ok(c.write_register(24, 512, slave=SLAVE), "06 S6")
    regs = ok(c.read_holding_registers(0, count=26, slave=SLAVE), "03").registers
    if regs[3] != 42 or regs[16:18] != [1000, 65535] or regs[24] != 512:
        fail(f"03 read back {regs}")
    print("03 06 16: presets and set-points written and read back")
    exception(c.write_register(5, 256, slave=SLAVE), 3, "06 T5 = 256")
    exception(c.write_register(25, 1024, slave=SLAVE), 3, "06 S7 = 1024")
    exception(c.write_registers(24, [100, 2000], slave=SLAVE), 3, "16 S6 S7 = 100 2000")
    if ok(c.read_holding_registers(24, count=2, slave=SLAVE), "03").registers != [512, 0]:
        fail("a refused write changed something")
    exception(c.read_holding_registers(26, count=1, slave=SLAVE), 2, "03 past the map")
    exception(c.read_input_registers(18, count=1, slave=SLAVE), 2, "04 in the gap 18..31")
    reply = raw(c, [0x03, 0, 0, 0, 126])
    if reply[:3] != bytes([SLAVE, 0x83, 3]) or crc16(reply) != 0:
        fail(f"03 of 126: {reply.hex()}")
    print("03 of 126: exception 3")
    # 05 / 15 / 01: coil U0 (8) on, V0..V7 (16..23) as a pattern.
    ok(c.write_coil(8, True, slave=SLAVE), "05 U0")
    ok(c.write_coils(16, [True, False, True, True, False, False, False, True], slave=SLAVE), "15 V")
    bits = ok(c.read_coils(0, count=24, slave=SLAVE), "01").bits
    if not bits[8] or bits[16:24] != [True, False, True, True, False, False, False, True]:
        fail(f"01 read back {bits[:24]}")
    print("01 05 15: coils written and read back")
    ok(c.write_coil(8, False, slave=SLAVE), "05 U0 off")
    # 02: A0..A5 open (1), addresses 6 and 7 outside the map.
    bits = ok(c.read_discrete_inputs(0, count=6, slave=SLAVE), "02").bits
    if bits[:6] != [True] * 6:
        fail(f"02 A0..A5 {bits[:6]}")
    exception(c.read_discrete_inputs(0, count=8, slave=SLAVE), 2, "02 over 6 and 7")
    ok(c.read_discrete_inputs(8, count=42, slave=SLAVE), "02 Q TQ CQ H")
    print("02: inputs read")
    # 04: status (running, a stored image), scans counting up.
    ir = ok(c.read_input_registers(0, count=18, slave=SLAVE), "04").registers
    if ir[0] & 0b101 != 0b101:
        fail(f"04 status {ir[0]:#06x}")
    scans = ir[4] << 16 | ir[5]
    ok(c.read_input_registers(32, count=16, slave=SLAVE), "04 time left")
    print(f"04: status {ir[0]:#06x}, {scans} scans")
    # 08 sub-function 0 echoes; 17 names the slave.
    echo = ok(c.diag_query_data(msg=b"\x12\x34", slave=SLAVE), "08")
    print("08: echo", echo.message)
    ident = ok(c.report_slave_id(slave=SLAVE), "17")
    if b"uTile" not in ident.identifier:
        fail(f"17 {ident.identifier}")
    print("17:", ident.identifier.decode(errors="replace"))
    # An unserved function: 24 (read FIFO queue) gets exception 01.
    exception(c.read_fifo_queue(address=0, slave=SLAVE), 1, "24 unserved")
    print("ALL OK")


def silent(c, frame, what):
    """A frame that must get no answer at all."""
    time.sleep(0.05)  # the silence a master leaves before a frame
    c.socket.reset_input_buffer()
    c.socket.write(frame)
    time.sleep(0.3)
    got = c.socket.read(c.socket.in_waiting or 0) if c.socket.in_waiting else b""
    if got:
        fail(f"{what}: answered {got.hex()}")
    print(f"{what}: no answer")


def wire(c):
    good = bytes([SLAVE, 0x03, 0, 0, 0, 1])
    silent(c, good + ((crc16(good) ^ 0x0101).to_bytes(2, "little")), "bad CRC")
    other = bytes([SLAVE + 1, 0x03, 0, 0, 0, 1])
    silent(c, other + crc16(other).to_bytes(2, "little"), "another address")
    # Broadcast: write coil V7 (23) on; no answer, but it is done.
    bcast = bytes([0, 0x05, 0, 23, 0xFF, 0])
    silent(c, bcast + crc16(bcast).to_bytes(2, "little"), "broadcast")
    if not ok(c.read_coils(23, count=1, slave=SLAVE), "01 V7").bits[0]:
        fail("the broadcast write was not done")
    ir = ok(c.read_input_registers(7, count=1, slave=SLAVE), "04 dropped").registers[0]
    if ir < 2:
        fail(f"dropped frames {ir}")
    print(f"broadcast done; {ir} frames dropped")
    print("ALL OK")


def windows(c):
    snap = ok(c.read_input_registers(64, count=40, slave=SLAVE), "04 snapshot").registers
    if len(snap) != 40:
        fail(f"snapshot of {len(snap)} registers")
    ir = ok(c.read_input_registers(0, count=8, slave=SLAVE), "04 status").registers
    if snap[0] != ir[0]:
        fail(f"status {snap[0]:#06x} in the snapshot, {ir[0]:#06x} in register 0")
    print("status", f"{snap[0]:#06x}")
    print("bits", " ".join(f"{w:#06x}" for w in snap[1:6]))
    print("scans", snap[6] << 16 | snap[7])
    print("readings", snap[16], snap[17])
    print("fingerprint", f"{snap[39]:04X}")
    words = ok(c.read_input_registers(256, count=125, slave=SLAVE), "04 program").registers
    words += ok(c.read_input_registers(381, count=3, slave=SLAVE), "04 program end").registers
    print("program", "".join(f"{w:04X}" for w in words))
    for start, n in [(63, 2), (103, 2), (104, 1), (255, 2), (383, 2), (384, 1)]:
        exception(c.read_input_registers(start, count=n, slave=SLAVE), 2, f"04 {start} x {n}")
    print("ALL OK")


HELD, LAPSED = 1 << 4, 1 << 5


def picture(c):
    """Status, Y0..Y7 and the scan count, from one read of the snapshot."""
    r = ok(c.read_input_registers(64, count=8, slave=SLAVE), "04 snapshot").registers
    return r[0], r[1] >> 8, r[6] << 16 | r[7]


def hold(c):
    if ok(c.read_holding_registers(32, count=2, slave=SLAVE), "03 32-33").registers != [0, 0]:
        fail("RUN did not start free")
    ok(c.write_register(32, 1, slave=SLAVE), "06 hold")
    status, y, scans = picture(c)
    if not status & HELD or y != scans & 0xFF:
        fail(f"held: status {status:#06x}, Y {y}, {scans} scans")
    time.sleep(0.5)
    if picture(c) != (status, y, scans):
        fail("the scan count moved while held")
    print(f"held at scan {scans}")
    for n in [1, 10, 1000]:
        ok(c.write_register(33, n, slave=SLAVE), f"06 {n} steps")
        # Until every step has run (register 33 counts them down), then held.
        deadline = time.time() + 10
        while ok(c.read_holding_registers(32, count=2, slave=SLAVE), "03").registers != [1, 0]:
            if time.time() > deadline:
                fail(f"{n} steps never all ran")
            time.sleep(0.1)
        time.sleep(0.3)
        _, y, now = picture(c)
        if now != scans + n or y != now & 0xFF:
            fail(f"{n} steps: {scans} -> {now} scans, Y {y}")
        print(f"{n} steps: {scans} -> {now} scans")
        scans = now
    for addr, value in [(32, 2), (33, 0), (33, 1001)]:
        exception(c.write_register(addr, value, slave=SLAVE), 3, f"06 {addr} = {value}")
    exception(c.write_registers(32, [0, 0], slave=SLAVE), 3, "16 32-33 = 0 0")
    exception(c.read_holding_registers(26, count=8, slave=SLAVE), 2, "03 26 x 8")
    if picture(c)[2] != scans:
        fail("a refused write released the hold")
    ok(c.write_register(32, 0, slave=SLAVE), "06 release")
    time.sleep(0.2)
    status, _, now = picture(c)
    if status & HELD or now <= scans:
        fail(f"released: status {status:#06x}, {scans} -> {now} scans")
    print("released: the scan runs")
    # The lease: a master that says nothing for 10 s leaves the plant running. The virtual
    # Nano keeps no long silence apart from its own pace, which a loaded host slows: each
    # read renews the lease, so the silences grow until one lasted 10 s of its time.
    ok(c.write_register(32, 1, slave=SLAVE), "06 hold")
    _, _, scans = picture(c)
    for wait in [11, 20, 40]:
        time.sleep(wait)
        status, _, now = picture(c)
        if status & HELD == 0:
            break
        if now != scans:
            fail(f"held, yet {scans} -> {now} scans")
    if status & (HELD | LAPSED) != LAPSED or now <= scans:
        fail(f"{wait} s of silence: status {status:#06x}, {scans} -> {now} scans")
    print(f"the lease ended the hold by itself: status {status:#06x}")
    print("ALL OK")


def bus(c, n):
    for s in range(1, n + 1):
        # Coil 8 + s is U(s): with PU. .PY, output Y(s) of slave s only.
        ok(c.write_coil(8 + s, True, slave=s), f"05 slave {s}")
    for s in range(1, n + 1):
        bits = ok(c.read_coils(0, count=8, slave=s), f"01 slave {s}").bits[:8]
        want = [i == s for i in range(8)]
        if bits != want:
            fail(f"slave {s} outputs {bits}, expected {want}")
        print(f"slave {s}: Y{s} on, the others off")
    # A broadcast: U0 on in every slave, nobody answers.
    frame = bytes([0, 0x05, 0, 8, 0xFF, 0])
    silent(c, frame + crc16(frame).to_bytes(2, "little"), "broadcast")
    for s in range(1, n + 1):
        if not ok(c.read_coils(0, count=1, slave=s), f"01 slave {s}").bits[0]:
            fail(f"slave {s} missed the broadcast")
    print("broadcast reached every slave")
    print("ALL OK")


def main():
    global SLAVE
    port, what = sys.argv[1], sys.argv[2]
    if what == "slave":
        SLAVE = int(sys.argv[3])
        del sys.argv[2:4]
        what = sys.argv[2]
    c = ModbusSerialClient(port=port, baudrate=19200, parity="N", stopbits=1, bytesize=8,
                           timeout=1, retries=2)
    if not c.connect():
        fail("cannot open " + port)
    if what == "functions":
        functions(c)
    elif what == "wire":
        wire(c)
    elif what == "windows":
        windows(c)
    elif what == "hold":
        hold(c)
    elif what == "bus":
        bus(c, int(sys.argv[3]))
    elif what == "poll":
        for k in range(int(sys.argv[3])):
            ok(c.read_coils(0, count=8, slave=SLAVE), f"poll {k}")
        print("ALL OK")
    elif what == "read":
        table, a, n = sys.argv[3], int(sys.argv[4]), int(sys.argv[5])
        call = {"co": c.read_coils, "di": c.read_discrete_inputs,
                "hr": c.read_holding_registers, "ir": c.read_input_registers}[table]
        r = ok(call(a, count=n, slave=SLAVE), "read")
        values = r.bits[:n] if table in ("co", "di") else r.registers
        print(" ".join(str(int(v)) for v in values))
    elif what == "coil":
        ok(c.write_coil(int(sys.argv[3]), sys.argv[4] == "1", slave=SLAVE), "coil")
        print("ok")
    elif what == "reg":
        ok(c.write_register(int(sys.argv[3]), int(sys.argv[4]), slave=SLAVE), "reg")
        print("ok")
    else:
        fail("unknown command " + what)
    c.close()


if __name__ == "__main__":
    main()
