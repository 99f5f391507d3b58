// Text output: strings from flash, decimal integers, CR LF (one writer: the main loop).
#include "textout.h"

#include <avr/pgmspace.h>
#include <stdlib.h>

#include "hal.h"

void out_P(PGM_P s) {
    for (char c; (c = pgm_read_byte(s)); s++) uart_put(c);
}
void out_s(const char *s) {
    while (*s) uart_put(*s++);
}
void out_i(int32_t v) {
    char buf[12];
    out_s(ltoa(v, buf, 10));
}
void out_u(uint32_t v) {
    char buf[11];
    out_s(ultoa(v, buf, 10));
}
void comma_i(int32_t v) {
    uart_put(',');
    out_i(v);
}
void end_line() {
    uart_put('\r');
    uart_put('\n');
}

