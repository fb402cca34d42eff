/* A tiny stand-in firmware for the virtual Nano's own tests (built with avr-gcc by
 * tools/tests/vnano_rig.rs). It uses the same pins as uTile, so the tests can check the
 * rig, the UART bridge, the EEPROM and the reset without depending on the real editor.
 *
 * - at boot: prints "BOOT mcusr=XX d8=N d9=N eeprom0=XX\r\n"
 * - mirrors the inputs to the outputs: Y0..Y5 lit while A0..A5 are pressed (pin low),
 *   Y6 lit while D8 is grounded, Y7 while D9 is grounded; PORTB is rewritten on every
 *   pass (with the pull-up bits) to provoke simavr's forgetting of driven inputs
 * - prints "IN=XX\r\n" (PINC & 0x3F | D8 << 6 | D9 << 7, active high) after the boot line
 *   and whenever it changes
 * - echoes every received byte, except:
 *     '+'  increments EEPROM byte 0 and prints "EE=XX\r\n"
 *     '#'  prints "N=XXXX\r\n": the number of bytes received so far (hex)
 */
#include <avr/io.h>
#include <avr/eeprom.h>

static void tx(uint8_t c) {
    while (!(UCSR0A & (1 << UDRE0))) {}
    UDR0 = c;
}

static void hex8(uint8_t v) {
    const char *d = "0123456789ABCDEF";
    tx(d[v >> 4]);
    tx(d[v & 15]);
}

static void str(const char *s) {
    while (*s) tx(*s++);
}

static uint8_t inputs(void) {
    uint8_t c = (uint8_t)(~PINC) & 0x3F;
    uint8_t b = (uint8_t)(~PINB) & 0x03;
    return c | (uint8_t)(b << 6);
}

int main(void) {
    uint8_t mcusr = MCUSR;
    MCUSR = 0;
    PORTC = 0x3F;            /* pull-ups on A0..A5 */
    PORTB = 0x03;            /* pull-ups on D8, D9 */
    DDRD = 0xFC;             /* Y0..Y5 */
    DDRB = 0x30;             /* Y6, Y7 */
    UBRR0 = 51;              /* 19200 baud at 16 MHz */
    UCSR0C = 3 << UCSZ00;
    UCSR0B = (1 << RXEN0) | (1 << TXEN0);

    uint8_t in = inputs();
    str("BOOT mcusr=");
    hex8(mcusr);
    str(" d8=");
    tx((in & 0x40) ? '1' : '0');
    str(" d9=");
    tx((in & 0x80) ? '1' : '0');
    str(" eeprom0=");
    hex8(eeprom_read_byte((uint8_t *)0));
    str("\r\n");

    uint16_t count = 0;
    uint8_t last = 0xFF;  /* report the first reading too */
    for (;;) {
        in = inputs();
        PORTD = (uint8_t)((in & 0x3F) << 2);
        PORTB = 0x03 | (uint8_t)(((in >> 6) & 0x03) << 4);
        if (in != last) {
            last = in;
            str("IN=");
            hex8(in);
            str("\r\n");
        }
        if (UCSR0A & (1 << RXC0)) {
            uint8_t c = UDR0;
            count++;
            if (c == '+') {
                uint8_t v = eeprom_read_byte((uint8_t *)0) + 1;
                eeprom_update_byte((uint8_t *)0, v);
                str("EE=");
                hex8(v);
                str("\r\n");
            } else if (c == '#') {
                str("N=");
                hex8((uint8_t)(count >> 8));
                hex8((uint8_t)count);
                str("\r\n");
            } else {
                tx(c);
            }
        }
    }
}
