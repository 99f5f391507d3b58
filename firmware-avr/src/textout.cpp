// Text output: strings from flash, decimal integers, CR LF (one writer: the main loop).
#include "textout.h"

#include <avr/pgmspace.h>
#include <stdlib.h>

#include "hal.h"

ReplySuffix reply_suffix;
static uint16_t line_crc = 0xFFFF;  // of the line so far, while the command answered had a check

uint16_t crc16_update(uint16_t crc, uint8_t b) {
    crc ^= (uint16_t)b << 8;
    for (uint8_t i = 0; i < 8; i++) crc = crc & 0x8000 ? (crc << 1) ^ 0x1021 : crc << 1;
    return crc;
}

void out_c(char c) {
    if (reply_suffix.check) line_crc = crc16_update(line_crc, c);
    uart_put(c);
}
void out_P(PGM_P s) {
    for (char c; (c = pgm_read_byte(s)); s++) out_c(c);
}
void out_s(const char *s) {
    while (*s) out_c(*s++);
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
    out_c(',');
    out_i(v);
}
void end_line() {
    uart_put('\r');
    uart_put('\n');
    line_crc = 0xFFFF;
}
void end_reply() {
    ReplySuffix &r = reply_suffix;
    if (r.tag_len) {
        out_c('#');
        for (uint8_t i = 0; i < r.tag_len; i++) out_c(r.tag[i]);
    }
    if (r.check) {
        uint16_t crc = line_crc;
        uart_put('*');
        for (int8_t shift = 12; shift >= 0; shift -= 4) {
            uint8_t d = (crc >> shift) & 0xF;
            uart_put(d < 10 ? '0' + d : 'A' + d - 10);
        }
    }
    end_line();
}
