// Text output helpers for reply and event lines, and the tag and check suffix of replies
// (docs/protocol.md "Tags and checks (text)", protocol/linecheck.py).
#pragma once
#include <avr/pgmspace.h>
#include <stdint.h>

void out_c(char c);
void out_P(PGM_P s);
void out_s(const char *s);
void out_i(int32_t v);
void out_u(uint32_t v);
void comma_i(int32_t v);  // ",<v>"
void end_line();          // CR LF: events (never tagged)
void end_reply();         // the command's "#tag" and "*check" if it had them, then CR LF

// CRC-16/CCITT-FALSE (poly 0x1021, no reflection), one byte on; start with 0xFFFF.
uint16_t crc16_update(uint16_t crc, uint8_t b);

// The suffix of the command being answered: its tag (0..4 digits) and whether it had a check.
struct ReplySuffix {
    char tag[4];
    uint8_t tag_len;
    bool check;
};
extern ReplySuffix reply_suffix;
