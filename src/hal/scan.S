; The threaded scan: RUN mode's interpreter for the ATmega328P, assembled into the firmware by
; `global_asm!` in scan.rs, which first defines the U_* (RAM addresses of the engine's
; fields, of the ticker's clock and edge bits, of the output image and of the receive ring),
; ST_* (RunState offsets), EXIT_* and VIEW_* symbols used here, and GPIOR0_IO / NOW_BIT (the
; main loop wanted at the next END, want.rs). The rules it follows are the core's (`Engine::scan`); the on-chip
; differential check (`--features scan-check`, tests/simavr_scan_check.rs) holds it to them.
;
; Dispatch: X points at the next UF line. `ld r30, X+` / `ijmp` jumps into a 256-word table
; of `rjmp`s aligned on a 256-word page (r31 holds the page number all the time), so one
; line costs 6 cycles of dispatch plus its own work. A NOP or blank line is just that.
; Line "256" is the engine's END guard, so nothing counts lines.
;
; Registers while scanning (everything the engine changes in a scan, except timer
; deadlines and the display requests, lives in registers):
;   r2:r3 S latches   r4:r5 R latches   r6:r7 Q   r8:r9 TQ
;   r10:r11 Timer1 at the last END   r12:r13 shortest scan   r14:r15 longest scan
;   r16:r17 scans (wraps: exit)
;   r18 bit stack (bit 0 = TOS)   r19 PY   r20 PU   r21 PV
;   r28 counter inputs CU   r29 counter inputs at the last END
;   r22..r25, r0, r1, r30 scratch   X next line   r31 table page
; Interrupts stay enabled; `cli`/`sei` only guard the read-modify-write of state that the
; 1 ms tick also writes (edge bits, ms clock, output pins).

; I/O addresses (PORTB_IO, PORTD_IO, TCNT1_MEM: regs.rs), pin masks (PORTB_Y, PORTD_Y,
; PORTB_PULLUPS, DE_BIT: pins.rs) and the timer units (UNIT_*: the core's TIMER_UNIT_MS) are
; also `.set` by scan.rs, from the Rust that names them.

.macro NEXT
    ld r30, X+
    ijmp
.endm

; Push bit \bit of register \reg.
.macro PUSH_REG reg, bit
    bst \reg, \bit
    lsl r18
    bld r18, 0
    NEXT
.endm

; Push bit \bit of the RAM byte at \addr (a one-byte load is atomic).
.macro PUSH_RAM addr, bit
    lds r22, \addr
    bst r22, \bit
    lsl r18
    bld r18, 0
    NEXT
.endm

; Push and clear sticky edge bit \bit at \addr. The tick sets these bits, so the clear is
; done with interrupts off (in \tail, shared by the six bits of \addr, with the mask in
; r23); a 0 (the usual case) needs no clear.
.macro TAKE_EDGE addr, bit, tail
    lsl r18
    lds r22, \addr
    sbrc r22, \bit
    rjmp 1f
    NEXT
1:  ldi r23, 0xFF - (1 << \bit)
    rjmp \tail
.endm

; The slow half of TAKE_EDGE: clear the bits of \addr that r23 holds at 0, push a 1.
.macro EDGE_TAIL addr
    cli
    lds r22, \addr
    and r22, r23
    sts \addr, r22
    sei
    ori r18, 1
    NEXT
.endm

; Pop into bit \bit of register \reg.
.macro POP_REG reg, bit
    bst r18, 0
    lsr r18
    bld \reg, \bit
    NEXT
.endm

; .TRm: a popped 1 stops timer m (its TQ bit \bit of \reg).
.macro POP_TR reg, bit
    bst r18, 0
    lsr r18
    brtc 1f
    clt
    bld \reg, \bit
1:  NEXT
.endm

; .TKm: a popped 1 (re)starts timer m unless its preset is 0: TQ rises at once, and the
; tail \tail computes deadline m = now + preset x unit, with Z at deadline m.
.macro POP_TK m, reg, bit, tail
    bst r18, 0
    lsr r18
    brts 1f
    NEXT
1:  lds r22, U_PRESETS + \m
    tst r22
    breq 2f
    bld \reg, \bit
    ldi r30, lo8(U_DEADLINE + 4 * \m)
    ldi r31, hi8(U_DEADLINE + 4 * \m)
    rjmp \tail
2:  NEXT
.endm

; Deadline at Z := ms clock + r1:r0 (as 32 bits, r23 = 0), then back to dispatch.
.macro ADD_NOW_16
    cli
    lds r22, U_MS
    add r22, r0
    st Z+, r22
    lds r22, U_MS + 1
    adc r22, r1
    st Z+, r22
    lds r22, U_MS + 2
    adc r22, r23
    st Z+, r22
    lds r22, U_MS + 3
    adc r22, r23
    st Z, r22
    sei
    ldi r31, pm_hi8(utile_scan_table)
    NEXT
.endm

; Deadline at Z := ms clock + preset (r22) x (\hi * 256 + \lo), a product below 2^24.
.macro TK_TAIL_24 lo, hi
    ldi r23, \lo
    mul r22, r23
    movw r24, r0
    ldi r23, \hi
    mul r22, r23
    add r25, r0
    clr r23
    adc r1, r23
    cli
    lds r22, U_MS
    add r22, r24
    st Z+, r22
    lds r22, U_MS + 1
    adc r22, r25
    st Z+, r22
    lds r22, U_MS + 2
    adc r22, r1
    st Z+, r22
    lds r22, U_MS + 3
    adc r22, r23
    st Z, r22
    sei
    ldi r31, pm_hi8(utile_scan_table)
    NEXT
.endm

; ---------------------------------------------------------------------------------------
; Cold code: entry, exit, END's rare branches, the timer sweep, the .TK tails. It sits in
; front of the table, where the page alignment would otherwise leave a gap.
    .pushsection .progmem.gcc.utile_scan_a, "ax", @progbits
    .p2align 1

; u8 utile_run(Engine *eng /* r25:r24 */, RunState *st /* r23:r22 */)
; Runs scans until KEY finds a received byte, the scan count wraps, (every 16th scan) the
; editor wants the CPU (U_WANT or a display request), or (after any END) the Modbus line
; does (NOW_BIT). At least one scan runs first. Returns why in r24.
    .global utile_run
    .type utile_run, @function
utile_run:
    push r2
    push r3
    push r4
    push r5
    push r6
    push r7
    push r8
    push r9
    push r10
    push r11
    push r12
    push r13
    push r14
    push r15
    push r16
    push r17
    push r28
    push r29
    push r22
    push r23
    movw r30, r22
    ldd r10, Z+ST_LAST
    ldd r11, Z+ST_LAST+1
    ldd r12, Z+ST_MIN
    ldd r13, Z+ST_MIN+1
    ldd r14, Z+ST_MAX
    ldd r15, Z+ST_MAX+1
    ldd r16, Z+ST_SCANS
    ldd r17, Z+ST_SCANS+1
    ldd r24, Z+ST_NEXT
    ldd r25, Z+ST_NEXT+1
    lds r18, U_BS
    lds r19, U_PY
    lds r20, U_PU
    lds r21, U_PV
    lds r2, U_SET
    lds r3, U_SET + 1
    lds r4, U_RESET
    lds r5, U_RESET + 1
    lds r6, U_Q
    lds r7, U_Q + 1
    lds r8, U_TQ
    lds r9, U_TQ + 1
    lds r28, U_CU
    lds r29, U_CU_PREV
    ldi r31, pm_hi8(utile_scan_table)
    ; next = 0: a new scan (sweep first); else the line after a KEY.
    ldi r26, lo8(U_UF)
    ldi r27, hi8(U_UF)
    add r26, r24
    adc r27, r25
    or r24, r25
    brne 1f
    rjmp utile_scan_start
1:  NEXT

; r24 = exit reason, X = next line (line 0 for "start a new scan").
utile_scan_exit:
    sts U_BS, r18
    sts U_PY, r19
    sts U_PU, r20
    sts U_PV, r21
    sts U_SET, r2
    sts U_SET + 1, r3
    sts U_RESET, r4
    sts U_RESET + 1, r5
    sts U_Q, r6
    sts U_Q + 1, r7
    sts U_TQ, r8
    sts U_TQ + 1, r9
    sts U_CU, r28
    sts U_CU_PREV, r29
    pop r31
    pop r30
    subi r26, lo8(U_UF)
    sbci r27, hi8(U_UF)
    std Z+ST_NEXT, r26
    std Z+ST_NEXT+1, r27
    std Z+ST_LAST, r10
    std Z+ST_LAST+1, r11
    std Z+ST_MIN, r12
    std Z+ST_MIN+1, r13
    std Z+ST_MAX, r14
    std Z+ST_MAX+1, r15
    std Z+ST_SCANS, r16
    std Z+ST_SCANS+1, r17
    clr r1
    pop r29
    pop r28
    pop r17
    pop r16
    pop r15
    pop r14
    pop r13
    pop r12
    pop r11
    pop r10
    pop r9
    pop r8
    pop r7
    pop r6
    pop r5
    pop r4
    pop r3
    pop r2
    ret
    .size utile_run, . - utile_run

; Every 16th END (the scan count's high byte not yet carried into): leave for the editor
; if it asked, and when the scan count wrapped; else on as after any END.
utile_scan_every16:
    sbci r17, 0xFF
    mov r22, r16
    or r22, r17
    breq 1f
    lds r22, U_WANT
    lds r23, U_VIEWS
    or r22, r23
    brne utile_scan_leave
    rjmp utile_scan_check
1:  ldi r24, EXIT_WRAP
    rjmp 3f
; The main loop is wanted (by the editor, or now by the Modbus line: `utile_scan_busy`).
utile_scan_leave:
    ldi r24, EXIT_SCANS
3:  ldi r26, lo8(U_UF)
    ldi r27, hi8(U_UF)
    rjmp utile_scan_exit

; Start of a scan with timers running, once per ms: retire those whose time has come
; (now - deadline >= 0 as a signed 32-bit number), as `Engine::retire_timers` does.
utile_scan_sweep:
    sts U_SWEPT_MS, r22
    cli
    lds r0, U_MS
    lds r1, U_MS + 1
    lds r22, U_MS + 2
    lds r23, U_MS + 3
    sei
    ldi r30, lo8(U_DEADLINE)
    ldi r31, hi8(U_DEADLINE)
    ldi r24, 1
1:  mov r25, r8
    and r25, r24
    breq 2f
    ldd r25, Z+0
    cp r0, r25
    ldd r25, Z+1
    cpc r1, r25
    ldd r25, Z+2
    cpc r22, r25
    ldd r25, Z+3
    cpc r23, r25
    brmi 2f
    mov r25, r24
    com r25
    and r8, r25
2:  adiw r30, 4
    lsl r24
    brne 1b
    ldi r24, 1
3:  mov r25, r9
    and r25, r24
    breq 4f
    ldd r25, Z+0
    cp r0, r25
    ldd r25, Z+1
    cpc r1, r25
    ldd r25, Z+2
    cpc r22, r25
    ldd r25, Z+3
    cpc r23, r25
    brmi 4f
    mov r25, r24
    com r25
    and r9, r25
4:  adiw r30, 4
    lsl r24
    brne 3b
    ldi r31, pm_hi8(utile_scan_table)
    rjmp utile_scan_go

; .TRm. These sit in front of the table too, filling most of the gap the table's page
; alignment leaves (`cargo fw` prints what is left of it).
    .irp n,0,1,2,3,4,5,6,7
utile_scan_tr\n:
    POP_TR r8, \n
    .endr
    .irp n,8,9,10,11,12,13,14,15
utile_scan_tr\n:
    POP_TR r9, (\n-8)
    .endr

; .TK tails, by timer unit: 0.1 s, 1 s, 1 min.
utile_scan_tk_100:
    ldi r23, UNIT_TENTH
    mul r22, r23
    clr r23
    ADD_NOW_16
utile_scan_tk_1000:
    TK_TAIL_24 lo8(UNIT_SECOND), hi8(UNIT_SECOND)
utile_scan_tk_60000:
    TK_TAIL_24 lo8(UNIT_MINUTE), hi8(UNIT_MINUTE)

; .TKF (400 s = 0x061A80 ms): the product needs 32 bits; Z stays the table page.
utile_scan_tk_400000:
    ldi r23, lo8(UNIT_400S)
    mul r22, r23
    movw r24, r0
    ldi r23, hi8(UNIT_400S)
    mul r22, r23
    add r25, r0
    clr r23
    adc r1, r23
    mov r30, r1
    ldi r23, hh8(UNIT_400S)
    mul r22, r23
    add r30, r0
    clr r23
    adc r1, r23
    cli
    lds r22, U_MS
    add r22, r24
    sts U_DEADLINE + 4 * 15, r22
    lds r22, U_MS + 1
    adc r22, r25
    sts U_DEADLINE + 4 * 15 + 1, r22
    lds r22, U_MS + 2
    adc r22, r30
    sts U_DEADLINE + 4 * 15 + 2, r22
    lds r22, U_MS + 3
    adc r22, r1
    sts U_DEADLINE + 4 * 15 + 3, r22
    sei
    NEXT

; ALn. / ATn. with the edge seen (TAKE_EDGE): rare, so in front of the table.
utile_scan_leading:
    EDGE_TAIL U_LEADING
utile_scan_trailing:
    EDGE_TAIL U_TRAILING

; End of the cold code: `cargo fw` reports the gap from here to the table.
utile_scan_cold_end:

; ---------------------------------------------------------------------------------------
; The dispatch table (one `rjmp` per opcode, docs/OPCODES.md) and the hot handlers.
    .section .progmem.gcc.utile_scan_b, "ax", @progbits
    .p2align 9
utile_scan_table:
    rjmp utile_scan_next            ; 0x00 NOP
    rjmp utile_scan_end             ; 0x01 END
    rjmp utile_scan_key             ; 0x02 KEY
    rjmp utile_scan_and             ; 0x03 AND
    rjmp utile_scan_or              ; 0x04 OR
    rjmp utile_scan_xor             ; 0x05 XOR
    rjmp utile_scan_not             ; 0x06 !
    rjmp utile_scan_not_all         ; 0x07 !!
    rjmp utile_scan_set             ; 0x08 SET
    rjmp utile_scan_clr             ; 0x09 CLR
    rjmp utile_scan_dup             ; 0x0A DUP
    rjmp utile_scan_drop            ; 0x0B DROP
    rjmp utile_scan_swap            ; 0x0C SWAP
    rjmp utile_scan_dup2            ; 0x0D 2DUP
    rjmp utile_scan_fill_ones       ; 0x0E F.
    rjmp utile_scan_fill_zeros      ; 0x0F Z.
    rjmp utile_scan_load_pa         ; 0x10 PA.
    rjmp utile_scan_load_py         ; 0x11 PY.
    rjmp utile_scan_load_pu         ; 0x12 PU.
    rjmp utile_scan_load_pv         ; 0x13 PV.
    rjmp utile_scan_store_py        ; 0x14 .PY
    rjmp utile_scan_store_pu        ; 0x15 .PU
    rjmp utile_scan_store_pv        ; 0x16 .PV
    rjmp utile_scan_ppa             ; 0x17 PPA
    rjmp utile_scan_ppy             ; 0x18 PPY
    rjmp utile_scan_ppu             ; 0x19 PPU
    rjmp utile_scan_ppv             ; 0x1A PPV
    rjmp utile_scan_pbs             ; 0x1B PBS
    rjmp utile_scan_clka            ; 0x1C CLKA.
    rjmp utile_scan_clkb            ; 0x1D CLKB.
    rjmp utile_scan_clkc            ; 0x1E CLKC.
    rjmp utile_scan_next            ; 0x1F unassigned
    .irp n,0,1,2,3,4,5
    rjmp utile_scan_a\n             ; 0x20 An.
    .endr
    rjmp utile_scan_h6              ; 0x26 H6.
    rjmp utile_scan_h7              ; 0x27 H7.
    .irp n,0,1,2,3,4,5
    rjmp utile_scan_al\n            ; 0x28 ALn.
    .endr
    .rept 2
    rjmp utile_scan_next
    .endr
    .irp n,0,1,2,3,4,5
    rjmp utile_scan_at\n            ; 0x30 ATn.
    .endr
    .rept 2
    rjmp utile_scan_next
    .endr
    .irp n,0,1,2,3,4,5
    rjmp utile_scan_ad\n            ; 0x38 ADn.
    .endr
    .rept 2
    rjmp utile_scan_next
    .endr
    .irp n,0,1,2,3,4,5,6,7
    rjmp utile_scan_y\n             ; 0x40 Yn.
    .endr
    .irp n,0,1,2,3,4,5,6,7
    rjmp utile_scan_u\n             ; 0x48 Un.
    .endr
    .irp n,0,1,2,3,4,5,6,7
    rjmp utile_scan_v\n             ; 0x50 Vn.
    .endr
    .irp n,0,1,2,3,4,5,6,7,8,9,10,11,12,13,14,15
    rjmp utile_scan_q\n             ; 0x58 Qm.
    .endr
    .irp n,0,1,2,3,4,5,6,7,8,9,10,11,12,13,14,15
    rjmp utile_scan_tq\n            ; 0x68 TQm.
    .endr
    .irp n,0,1,2,3,4,5,6,7
    rjmp utile_scan_cq\n            ; 0x78 CQm.
    .endr
    .irp n,0,1,2,3,4,5,6,7
    rjmp utile_scan_pop_y\n         ; 0x80 .Yn
    .endr
    .irp n,0,1,2,3,4,5,6,7
    rjmp utile_scan_pop_u\n         ; 0x88 .Un
    .endr
    .irp n,0,1,2,3,4,5,6,7
    rjmp utile_scan_pop_v\n         ; 0x90 .Vn
    .endr
    .irp n,0,1,2,3,4,5,6,7,8,9,10,11,12,13,14,15
    rjmp utile_scan_pop_s\n         ; 0x98 .Sm
    .endr
    .irp n,0,1,2,3,4,5,6,7,8,9,10,11,12,13,14,15
    rjmp utile_scan_pop_r\n         ; 0xA8 .Rm
    .endr
    .irp n,0,1,2,3,4,5,6,7,8,9,10,11,12,13,14,15
    rjmp utile_scan_tk\n            ; 0xB8 .TKm
    .endr
    .irp n,0,1,2,3,4,5,6,7,8,9,10,11,12,13,14,15
    rjmp utile_scan_tr\n            ; 0xC8 .TRm
    .endr
    .irp n,0,1,2,3,4,5,6,7
    rjmp utile_scan_cu\n            ; 0xD8 .CUm
    .endr
    .irp n,0,1,2,3,4,5,6,7
    rjmp utile_scan_cr\n            ; 0xE0 .CRm
    .endr
    .rept 24
    rjmp utile_scan_next            ; 0xE8..0xFF unassigned, 0xFF blank
    .endr
    .if . - utile_scan_table - 512
    .error "the dispatch table must have exactly 256 entries"
    .endif

; NOP, blank and unassigned lines: straight to the next line.
utile_scan_next:
    NEXT

; END: flip-flops, outputs, statistics, then the next scan.
utile_scan_end:
    ; Q = (Q or S) and not R, and the counters, skipped while every S and R is 0 and the
    ; count inputs are as at the last END.
    mov r22, r28
    eor r22, r29
    or r22, r2
    or r22, r3
    or r22, r4
    or r22, r5
    breq utile_scan_end_out
    or r6, r2
    or r7, r3
    mov r22, r4
    com r22
    and r6, r22
    mov r22, r5
    com r22
    and r7, r22
    cpse r28, r29
    rjmp utile_scan_count
utile_scan_end_out:
    lds r22, U_OUT_PY
    cp r22, r19
    breq utile_scan_stats
    rjmp utile_scan_outputs
utile_scan_stats:
    ; This scan's length in Timer1 counts (TCNT1L first: it latches TCNT1H).
    lds r22, TCNT1_MEM
    lds r23, TCNT1_MEM + 1
    movw r24, r22
    sub r22, r10
    sbc r23, r11
    movw r10, r24
    cp r22, r12
    cpc r23, r13
    brsh 2f
    movw r12, r22
2:  cp r14, r22
    cpc r15, r23
    brsh 3f
    movw r14, r22
    ; One scan more. H clear after `subi` (no borrow from bit 3) means the low nibble
    ; went from 15 to 0: every 16th scan. The high byte's carry is added after the branch.
3:  subi r16, 0xFF
    brhc utile_scan_16th
    sbci r17, 0xFF
; After an END the main loop may be wanted at once (GPIOR0's NOW bit: a Modbus frame ended,
; a reply needs bytes). The test costs one cycle: the flag joins the test for running
; timers, and only that slow path tells the two apart.
utile_scan_check:
    in r22, GPIOR0_IO
    wdr
    ldi r26, lo8(U_UF)
    ldi r27, hi8(U_UF)
    or r22, r8
    or r22, r9
    brne utile_scan_busy
utile_scan_go:
    NEXT
utile_scan_16th:
    rjmp utile_scan_every16
; A new scan on entry: as after an END, but the main loop's wish (NOW_BIT) is looked at
; only after this scan, so that one scan at least runs between two visits.
utile_scan_start:
    wdr
    ldi r26, lo8(U_UF)
    ldi r27, hi8(U_UF)
    mov r22, r8
    or r22, r9
    breq utile_scan_go
    rjmp utile_scan_timers
utile_scan_busy:
    sbic GPIOR0_IO, NOW_BIT
    rjmp utile_scan_leave
utile_scan_timers:
    lds r22, U_MS
    lds r23, U_SWEPT_MS
    cp r22, r23
    breq utile_scan_go
    rjmp utile_scan_sweep

; KEY: with a byte received, leave so the editor can look at it.
utile_scan_key:
    lds r22, U_RX_HEAD
    lds r23, U_RX_TAIL
    cp r22, r23
    brne 1f
    NEXT
1:  ldi r24, EXIT_KEY
    rjmp utile_scan_exit

; Two popped, their AND / OR / XOR pushed: bit 0 of r22 is the old TOS.
utile_scan_and:
    mov r22, r18
    lsr r18
    and r22, r18
    bst r22, 0
    bld r18, 0
    NEXT
utile_scan_or:
    mov r22, r18
    lsr r18
    or r22, r18
    bst r22, 0
    bld r18, 0
    NEXT
utile_scan_xor:
    mov r22, r18
    lsr r18
    eor r22, r18
    bst r22, 0
    bld r18, 0
    NEXT
utile_scan_not:
    ldi r22, 1
    eor r18, r22
    NEXT
utile_scan_not_all:
    com r18
    NEXT
utile_scan_set:
    sec
    rol r18
    NEXT
utile_scan_clr:
    lsl r18
    NEXT
utile_scan_dup:
    PUSH_REG r18, 0
utile_scan_drop:
    lsr r18
    NEXT
utile_scan_swap:
    mov r22, r18
    bst r22, 1
    bld r18, 0
    bst r22, 0
    bld r18, 1
    NEXT
utile_scan_dup2:
    mov r22, r18
    andi r22, 3
    lsl r18
    lsl r18
    or r18, r22
    NEXT
utile_scan_fill_ones:
    ldi r18, 0xFF
    NEXT
utile_scan_fill_zeros:
    clr r18
    NEXT
utile_scan_load_pa:
    lds r18, U_LEVEL
    NEXT
utile_scan_load_py:
    mov r18, r19
    NEXT
utile_scan_load_pu:
    mov r18, r20
    NEXT
utile_scan_load_pv:
    mov r18, r21
    NEXT
utile_scan_store_py:
    mov r19, r18
    NEXT
utile_scan_store_pu:
    mov r20, r18
    NEXT
utile_scan_store_pv:
    mov r21, r18
    NEXT
utile_scan_ppa:
    lds r22, U_LEVEL
    rjmp utile_scan_port_view
utile_scan_ppy:
    mov r22, r19
    rjmp utile_scan_port_view
utile_scan_ppu:
    mov r22, r20
    rjmp utile_scan_port_view
utile_scan_ppv:
    mov r22, r21
utile_scan_port_view:
    sts U_PORT_VIEW, r22
    lds r22, U_VIEWS
    ori r22, VIEW_PORT
    sts U_VIEWS, r22
    NEXT
utile_scan_pbs:
    sts U_BS_VIEW, r18
    lds r22, U_VIEWS
    ori r22, VIEW_BS
    sts U_VIEWS, r22
    NEXT
utile_scan_clka:
    PUSH_RAM U_CLOCKS, 0
utile_scan_clkb:
    PUSH_RAM U_CLOCKS, 1
utile_scan_clkc:
    PUSH_RAM U_CLOCKS, 2

; END, PY changed: copy it to the pins (out_sense applied), as `drive_pins` does.
utile_scan_outputs:
    cli
    sts U_OUT_PY, r19
    sts U_LAST_PY, r19
    lds r22, U_OUT_INVERT
    eor r22, r19
    ; Y0..Y5 on PD2..PD7; PD0/PD1 (USART) keep their bits.
    in r23, PORTD_IO
    andi r23, lo8(~PORTD_Y)
    mov r24, r22
    lsl r24
    lsl r24
    or r23, r24
    out PORTD_IO, r23
    ; Y6/Y7 on PB4/PB5, pull-ups on PB0, PB1, PB3, the driver enable D10 (PB2) as it is;
    ; written only when it changes (simavr forgets a driven level on a pulled-up pin at
    ; every PORT write).
    mov r24, r22
    lsr r24
    lsr r24
    andi r24, PORTB_Y
    ori r24, PORTB_PULLUPS
    in r23, PORTB_IO
    mov r25, r23
    andi r25, DE_BIT
    or r24, r25
    cp r23, r24
    breq 1f
    out PORTB_IO, r24
1:  sei
    rjmp utile_scan_stats

; END with a count input changed: each 0 -> 1 change since the last END counts (saturating
; at 65535) unless the reset latch is 1, and sets CQ when the count reaches a preset other
; than 0, as `Engine::count_edges` does. Counts are 16 bits at U_COUNT, presets CP_OFF
; bytes further on.
utile_scan_count:
    lds r23, U_CR
    com r23
    mov r22, r29
    com r22
    and r22, r28
    mov r29, r28
    and r22, r23
    breq 5f
    ldi r30, lo8(U_COUNT)
    ldi r31, hi8(U_COUNT)
    ldi r23, 1
1:  sbrs r22, 0
    rjmp 4f
    ld r24, Z
    ldd r25, Z+1
    adiw r24, 1
    breq 4f
    st Z, r24
    std Z+1, r25
    ldd r0, Z+CP_OFF
    ldd r1, Z+CP_OFF+1
    cp r24, r0
    cpc r25, r1
    brlo 4f
    tst r0
    brne 3f
    tst r1
    breq 4f
3:  lds r0, U_CQ
    or r0, r23
    sts U_CQ, r0
4:  adiw r30, 2
    lsl r23
    lsr r22
    brne 1b
5:  ldi r31, pm_hi8(utile_scan_table)
    rjmp utile_scan_end_out

; .CRm with a 1: count m (at Z) and CQm (r23 = its mask, inverted) are 0 at once.
utile_scan_cr_tail:
    clr r22
    st Z, r22
    std Z+1, r22
    lds r22, U_CQ
    and r22, r23
    sts U_CQ, r22
    ldi r31, pm_hi8(utile_scan_table)
    NEXT

    .irp n,0,1,2,3,4,5
utile_scan_a\n:
    PUSH_RAM U_LEVEL, \n
utile_scan_al\n:
    TAKE_EDGE U_LEADING, \n, utile_scan_leading
utile_scan_at\n:
    TAKE_EDGE U_TRAILING, \n, utile_scan_trailing
utile_scan_ad\n:
    PUSH_RAM U_TOGGLES, \n
    .endr

    .irp n,0,1,2,3,4,5,6,7
utile_scan_y\n:
    PUSH_REG r19, \n
utile_scan_u\n:
    PUSH_REG r20, \n
utile_scan_v\n:
    PUSH_REG r21, \n
utile_scan_q\n:
    PUSH_REG r6, \n
utile_scan_tq\n:
    PUSH_REG r8, \n
utile_scan_pop_y\n:
    POP_REG r19, \n
utile_scan_pop_u\n:
    POP_REG r20, \n
utile_scan_pop_v\n:
    POP_REG r21, \n
utile_scan_pop_s\n:
    POP_REG r2, \n
utile_scan_pop_r\n:
    POP_REG r4, \n
    .endr

    .irp n,8,9,10,11,12,13,14,15
utile_scan_q\n:
    PUSH_REG r7, (\n-8)
utile_scan_tq\n:
    PUSH_REG r9, (\n-8)
utile_scan_pop_s\n:
    POP_REG r3, (\n-8)
utile_scan_pop_r\n:
    POP_REG r5, (\n-8)
    .endr

; H6. H7. CQm. .CUm .CRm (image format 2).
utile_scan_h6:
    PUSH_RAM U_HBITS, 6
utile_scan_h7:
    PUSH_RAM U_HBITS, 7
    .irp n,0,1,2,3,4,5,6,7
utile_scan_cq\n:
    PUSH_RAM U_CQ, \n
utile_scan_cu\n:
    POP_REG r28, \n
utile_scan_cr\n:
    bst r18, 0
    lsr r18
    lds r22, U_CR
    bld r22, \n
    sts U_CR, r22
    brts 1f
    NEXT
1:  ldi r30, lo8(U_COUNT + 2 * \n)
    ldi r31, hi8(U_COUNT + 2 * \n)
    ldi r23, 0xFF - (1 << \n)
    rjmp utile_scan_cr_tail
    .endr

    .irp n,0,1,2,3
utile_scan_tk\n:
    POP_TK \n, r8, \n, utile_scan_tk_100
    .endr
    .irp n,4,5,6,7
utile_scan_tk\n:
    POP_TK \n, r8, \n, utile_scan_tk_1000
    .endr
    .irp n,8,9,10,11
utile_scan_tk\n:
    POP_TK \n, r9, (\n-8), utile_scan_tk_1000
    .endr
    .irp n,12,13,14
utile_scan_tk\n:
    POP_TK \n, r9, (\n-8), utile_scan_tk_60000
    .endr

; .TKF: the 400 s unit needs a 32-bit product (see utile_scan_tk_400000).
utile_scan_tk15:
    bst r18, 0
    lsr r18
    brts 1f
    NEXT
1:  lds r22, U_PRESETS + 15
    tst r22
    breq 2f
    bld r9, 7
    rjmp utile_scan_tk_400000
2:  NEXT
    .popsection
