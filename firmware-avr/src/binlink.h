// Binary mode (MODE bit 2, docs/protocol.md "Binary protocol", version 2): frames with their length,
// COBS and a CRC-32 over the bytes as sent, zigzag varints, sequence numbers, duplicate replies,
// event retransmission (firmware/binlink.py, protocol/frame.py, arq.py).
#pragma once
#include <stdint.h>

#include "features.h"

namespace bin {

// A new session (entering binary mode): forget frames, sequence state and waiting events.
void reset();
// One received byte; a complete good frame is handed to `on_frame` (declared below).
void feed(uint8_t c);
// Building one outgoing frame: begin, put the integers (and text), then send.
void begin(uint8_t type, uint8_t seq, bool sync = false);
void put(int32_t v);
void put_u32(uint32_t v);
void text_P(const char *s);  // from flash
void send_reply();           // a reply to the command being handled (kept for duplicates)
void send_plain();           // TEL: seq 0, neither kept nor acknowledged
// Events (RANGE, WARN, IDLE): sequenced, retransmitted until ACKed, backlogged while the window is full.
void event(uint8_t type, int16_t a, int16_t b, uint8_t n);
void poll(uint32_t now_ms);  // retransmissions and backlog, every main-loop pass
uint8_t seq();               // seq of the command being handled
uint8_t window();            // the send window we take (announced in the HELLO reply)

// Sequenced text (MODE bit 5): the tags of checked text commands as sequence numbers 1..9999.
void text_reset();                                  // the next tag is taken whatever it is
uint8_t text_classify(uint16_t tag, bool sync);     // NEW 0, DUPLICATE 1, OUT_OF_ORDER 2
void text_result(uint8_t code);                     // the reply sent: 0 OK, an ERROR code, 255 a query
void text_remember(uint16_t tag);                   // keep that reply for a duplicate of `tag`
int16_t text_kept(uint16_t tag);                    // the reply kept for `tag`, -1 if none

}  // namespace bin

// Provided by the controller: a received command frame, classified NEW (`type` is the command's
// id; `ints` hold `n` integers, n = 255 when the payload was not integers).
void on_frame(uint8_t type, int32_t *ints, uint8_t n);
// Provided by the controller: a duplicate STATUS or HELLO whose reply was not kept: answer again.
void on_query_again(uint8_t type);
uint32_t controller_ms();
