#include "binlink.h"

#include "board.h"
#include "hal.h"

namespace bin {

#define KEPT_BYTES BOARD_KEPT_BYTES  // replies up to this many frame bytes are kept; longer ones run again
#define EVENT_BYTES 12
#define BACKLOG BOARD_BACKLOG  // events waiting for the send window; more are dropped
#define CHUNK_MAX BOARD_CHUNK_MAX  // longer chunks are dropped unanswered (board.h)
#define FRAME_MAX 72      // largest frame we send (a TEL of every group, 32-bit extremes)

// The window this controller takes and announces in its HELLO reply: on the UNO the protocol's least.
// Each slot costs 20 B of kept reply and 19 B of pending event, and 8 command frames (at most 25 bytes
// each on the wire: 5 varints of 16 bits) fit in the 256-byte receive ring, so a host streaming
// commands that run slower than the line (a turning MOVE: 2.2 ms) can never overflow it (docs/uno.md).
// The Mega takes P_WINDOW (board.h): 32 frames fit its 1 KB ring. The host takes our events with its
// window of P_WINDOW, so W events in flight are within it.
static const uint8_t W = BOARD_WINDOW;
static_assert(BOARD_WINDOW >= P_WINDOW_MIN && BOARD_WINDOW <= P_WINDOW, "the window is P_WINDOW_MIN..P_WINDOW");
static_assert(BOARD_WINDOW * 25 <= BOARD_RX_SIZE, "a window of command frames fits the receive ring");
static const uint16_t RETRY_MS = P_RETRY_TIMEOUT_MS;
static const uint8_t RETRIES = P_RETRIES;

// Sequenced text (MODE bit 5; controller.py `_in_sequence`, arq.Receiver with tags 1..9999): the
// receiver of tagged, checked text commands. It lives in the frame buffer, which text mode leaves
// idle (the UNO has no RAM to spare); every switch of protocol resets both (text_reset, reset).
struct TextSeq {
    uint16_t expected;             // 0: the next tag is taken whatever it is
    uint16_t tag[P_TEXT_SEQ_WINDOW];
    uint8_t code[P_TEXT_SEQ_WINDOW];  // the reply kept: 0 OK, an ERROR code, 255 a query to run again
    uint8_t next, result;             // the slot to fill next; the reply of the command being answered
};
static_assert(sizeof(TextSeq) <= CHUNK_MAX, "the text sequence fits the frame buffer");
static union {
    uint8_t chunk[CHUNK_MAX];
    TextSeq text;
} buf;
static uint8_t *const chunk = buf.chunk;
static TextSeq &text = buf.text;
static uint8_t chunk_len;
static bool chunk_overflow;
static uint8_t out[FRAME_MAX];
static uint8_t out_len;
static bool out_overflow;
static uint8_t cur_seq;

// receiver (arq.Receiver)
static uint8_t expected;
struct Kept {
    uint8_t seq, len;  // len 0: free; 255: a query to run again
    uint8_t type;
    uint8_t data[KEPT_BYTES];
};
static Kept kept[W];
static uint8_t kept_next;

// sender (arq.Sender) for events
struct Pending {
    uint8_t seq, len, resent;
    uint32_t deadline;
    uint8_t data[EVENT_BYTES];
};
static Pending pending[W];
static uint8_t pending_n;
static uint8_t next_seq = 1;
static bool sync_flag = true;
struct Waiting {
    uint8_t type, n;
    int16_t a, b;
};
static Waiting backlog[BACKLOG];
static uint8_t backlog_head, backlog_n;

static uint8_t seq_next(uint8_t s) { return s % P_SEQ_MAX + 1; }
static uint8_t seq_back(uint8_t expect, uint8_t s) { return (uint8_t)(((int16_t)expect - s + P_SEQ_MAX) % P_SEQ_MAX); }

void reset() {
    chunk_len = 0;
    chunk_overflow = false;
    expected = 0;
    for (uint8_t i = 0; i < W; i++) kept[i].len = 0;
    pending_n = 0;
    next_seq = 1;
    sync_flag = true;
    backlog_n = 0;
}

uint8_t seq() { return cur_seq; }
uint8_t window() { return W; }

// CRC-32/ISO-HDLC (reflected 0xEDB88320, init and final XOR 0xFFFFFFFF) as protocol/crc.py, a nibble
// at a time from a 16-entry table in flash (64 B; a byte table would take 1 KB).
static const uint32_t CRC_NIBBLE[16] PROGMEM = {
    0x00000000UL, 0x1DB71064UL, 0x3B6E20C8UL, 0x26D930ACUL, 0x76DC4190UL, 0x6B6B51F4UL, 0x4DB26158UL, 0x5005713CUL,
    0xEDB88320UL, 0xF00F9344UL, 0xD6D6A3E8UL, 0xCB61B38CUL, 0x9B64C2B0UL, 0x86D3D2D4UL, 0xA00AE278UL, 0xBDBDF21CUL};

static uint32_t crc32_byte(uint32_t crc, uint8_t b) {
    crc ^= b;
    crc = pgm_read_dword(&CRC_NIBBLE[crc & 0x0F]) ^ (crc >> 4);
    return pgm_read_dword(&CRC_NIBBLE[crc & 0x0F]) ^ (crc >> 4);
}

static uint32_t crc32(const uint8_t *p, uint8_t n) {
    uint32_t crc = 0xFFFFFFFFUL;
    while (n--) crc = crc32_byte(crc, *p++);
    return ~crc;
}

static uint32_t wire_crc;
static void wire(uint8_t b) {
    wire_crc = crc32_byte(wire_crc, b);
    uart_put(b);
}

// Writes 00 | COBS(L | type | seq | payload) | K0..K4 | 00: the body is under 254 bytes (one COBS
// block); the CRC-32 covers the body as sent, in 5 check bytes of 7 bits with bit 7 set.
static void write_frame(const uint8_t *f, uint8_t n) {
    uart_put(0);
    wire_crc = 0xFFFFFFFFUL;
    uint8_t start = 0;
    for (uint8_t i = 0; i <= n; i++) {
        if (i == n || f[i] == 0) {
            wire(i - start + 1);
            for (uint8_t k = start; k < i; k++) wire(f[k]);
            start = i + 1;
        }
    }
    uint32_t crc = ~wire_crc;
    for (uint8_t k = 0; k < 5; k++, crc >>= 7) uart_put(0x80 | (crc & 0x7F));
    uart_put(0);
}

void begin(uint8_t type, uint8_t s, bool sync) {
    out[1] = sync ? type | P_FRAME_SYNC : type;
    out[2] = s;
    out_len = 3;
    out_overflow = false;
}

static void byte(uint8_t b) {
    if (out_len < FRAME_MAX) out[out_len++] = b;
    else out_overflow = true;
}

static void put_zigzag(uint32_t z) {
    while (z >= 0x80) {
        byte((z & 0x7F) | 0x80);
        z >>= 7;
    }
    byte(z);
}

void put(int32_t v) { put_zigzag(v >= 0 ? (uint32_t)v << 1 : (((uint32_t)(-(v + 1))) << 1) | 1); }

// An unsigned 32-bit value (TEL's t_ms): zigzag of a non-negative number needs 33 bits.
void put_u32(uint32_t v) {
    byte((v << 1 & 0x7F) | (v >= 0x40 ? 0x80 : 0));
    if (v >= 0x40) put_zigzag(v >> 6);  // the rest, 7 bits a byte, as an unsigned varint
}

void text_P(const char *s) {
    for (char c; (c = pgm_read_byte(s)); s++) byte(c);
}

// Sets L, the frame's length on the wire between its delimiters (COBS code byte, L .. payload, the
// 5 check bytes); the bytes to encode are out[0 .. out_len).
static uint8_t finish() {
    out[0] = out_len + 6;
    return out_len;
}

void send_reply() {
    uint8_t n = finish();
    Kept &k = kept[kept_next];
    kept_next = (kept_next + 1) % W;
    k.seq = out[2];
    k.type = out[1] & 0x7F;
    if (n <= KEPT_BYTES) {
        k.len = n;
        for (uint8_t i = 0; i < n; i++) k.data[i] = out[i];
    } else {
        k.len = 255;  // a query (STATUS, HELLO): answered again from the state of then
    }
    write_frame(out, n);
}

void send_plain() { write_frame(out, finish()); }

static void send_event(uint8_t type, int16_t a, int16_t b, uint8_t n, uint32_t now) {
    uint8_t s = next_seq;
    next_seq = seq_next(s);
    begin(type, s, sync_flag);
    sync_flag = false;
    if (n > 0) put(a);
    if (n > 1) put(b);
    uint8_t len = finish();
    Pending &p = pending[pending_n++];
    p.seq = s;
    p.len = len;
    p.resent = 0;
    p.deadline = now + RETRY_MS;
    for (uint8_t i = 0; i < len; i++) p.data[i] = out[i];
    write_frame(out, len);
}

// arq.Sender.ready: within the window, and nothing follows a SYNC frame before its ACK.
static bool ready() {
    return pending_n == 0 || (!(pending[0].data[1] & P_FRAME_SYNC) && seq_back(next_seq, pending[0].seq) < W);
}

void event(uint8_t type, int16_t a, int16_t b, uint8_t n) {
    if (backlog_n || !ready() || pending_n >= W) {
        if (backlog_n < BACKLOG) {
            Waiting &w = backlog[(backlog_head + backlog_n++) % BACKLOG];
            w.type = type;
            w.a = a;
            w.b = b;
            w.n = n;
        }
        return;
    }
    send_event(type, a, b, n, controller_ms());
}

static void ack(uint8_t s) {
    for (uint8_t i = 0; i < pending_n; i++) {
        if (pending[i].seq == s) {
            for (uint8_t k = i + 1; k < pending_n; k++) pending[k - 1] = pending[k];
            pending_n--;
            return;
        }
    }
}

void poll(uint32_t now) {
    for (uint8_t i = 0; i < pending_n; i++) {
        Pending &p = pending[i];
        if ((int32_t)(now - p.deadline) < 0) continue;
        if (p.resent >= RETRIES) {  // give up on it and every later one; the next frame is SYNC
            pending_n = i;
            sync_flag = true;
            break;
        }
        p.deadline = now + RETRY_MS;
        p.resent++;
        write_frame(p.data, p.len);
    }
    while (backlog_n && ready() && pending_n < W) {
        Waiting &w = backlog[backlog_head];
        backlog_head = (backlog_head + 1) % BACKLOG;
        backlog_n--;
        send_event(w.type, w.a, w.b, w.n, now);
    }
}

// NEW 0, DUPLICATE 1, OUT_OF_ORDER 2 (arq.Receiver.classify)
static uint8_t classify(uint8_t s, bool sync) {
    if (s == 0) return 2;  // seq 0 is never a command's: a replay can never run twice
    if (expected) {
        uint8_t back = seq_back(expected, s);
        if (back > 0 && back <= W) return 1;
        if (back && !sync) return 2;
    }
    expected = seq_next(s);
    return 0;
}

static void duplicate(uint8_t s) {
    for (uint8_t i = 0; i < W; i++) {
        Kept &k = kept[i];
        uint8_t back = seq_back(expected, k.seq);
        if (k.len && k.seq == s && back > 0 && back <= W) {
            if (k.len == 255) {
                cur_seq = s;
                on_query_again(k.type == T_HELLO_REPLY ? K_HELLO : K_STATUS);
            } else {
                write_frame(k.data, k.len);
            }
            return;
        }
    }
}

// One chunk between delimiters (frame.parse_frame): its length byte, check bytes, CRC-32 over the
// bytes as received, COBS, the length again. Anything wrong: dropped unanswered, the host retries.
static void frame(uint8_t *f, uint8_t n) {
    if (n < 9 || f[1] != n) return;
    uint8_t end = n - 5;
    uint32_t crc = 0;
    for (uint8_t k = 0; k < 5; k++) {
        if (f[end + k] < 0x80) return;
        crc |= (uint32_t)(f[end + k] & 0x7F) << (7 * k);
    }
    if (f[end + 4] > 0x8F || crc32(f, end) != crc) return;
    // COBS decode in place: the output is never longer than the input
    uint8_t i = 0, o = 0;
    while (i < end) {
        uint8_t code = f[i];
        if (code == 0 || i + code > end) return;
        for (uint8_t k = 1; k < code; k++) f[o++] = f[i + k];
        i += code;
        if (code != 0xFF && i < end) f[o++] = 0;
    }
    if (o != end - 1 || f[0] != n) return;
    f++;  // past L
    o--;
    uint8_t type = f[0] & 0x7F, s = f[1];
    bool sync = f[0] & P_FRAME_SYNC;
    if (type == T_ACK) {
        ack(s);
        return;
    }
    if (type == K_HELLO && sync) {
        expected = 0;
        for (uint8_t k = 0; k < W; k++) kept[k].len = 0;
    }
    uint8_t kind = classify(s, sync);
    if (kind == 1) return duplicate(s);
    if (kind == 2) return;
    cur_seq = s;
    int32_t ints[CMD_PARAMS_MAX + 1];
    uint8_t count = 0;
    end = o;
    for (uint8_t k = 2; k < end;) {
        uint32_t z = 0;
        uint8_t shift = 0;
        for (;;) {
            if (k >= end || shift >= 35) return on_frame(type, ints, 255);  // bad varint
            uint8_t b = f[k++];
            z |= (uint32_t)(b & 0x7F) << shift;
            if (shift == 28 && (b & 0x70)) z = 0xFFFFFFFF;  // past 32 bits: -2^31, beyond every field (34)
            shift += 7;
            if (b < 0x80) break;
        }
        if (count <= CMD_PARAMS_MAX) ints[count] = z & 1 ? -1 - (int32_t)(z >> 1) : (int32_t)(z >> 1);  // (z + 1) >> 1 wraps at 2^32 - 1
        if (count < 255) count++;
    }
    on_frame(type, ints, count);
}

void feed(uint8_t c) {
    if (c == 0) {
        if (chunk_len && !chunk_overflow) frame(chunk, chunk_len);
        chunk_len = 0;
        chunk_overflow = false;
    } else if (chunk_len < CHUNK_MAX) {
        chunk[chunk_len++] = c;
    } else {
        chunk_overflow = true;  // longer than any command frame: dropped up to the next 00
    }
}

// ------------------------------------------------------------------ sequenced text

void text_reset() {
    text.expected = 0;
    for (uint8_t i = 0; i < P_TEXT_SEQ_WINDOW; i++) text.tag[i] = 0;
}

static uint16_t text_back(uint16_t tag) { return (text.expected + P_TEXT_SEQ_MAX - tag) % P_TEXT_SEQ_MAX; }

uint8_t text_classify(uint16_t tag, bool sync) {
    if (tag == 0) return 2;
    if (text.expected) {
        uint16_t back = text_back(tag);
        if (back > 0 && back <= P_TEXT_SEQ_WINDOW) return 1;
        if (back && !sync) return 2;
    }
    text.expected = tag % P_TEXT_SEQ_MAX + 1;
    return 0;
}

void text_result(uint8_t code) { text.result = code; }

void text_remember(uint16_t tag) {
    text.tag[text.next] = tag;
    text.code[text.next] = text.result;
    text.next = (text.next + 1) % P_TEXT_SEQ_WINDOW;
}

int16_t text_kept(uint16_t tag) {
    for (uint8_t i = 0; i < P_TEXT_SEQ_WINDOW; i++) {
        uint16_t back = text_back(text.tag[i]);
        if (text.tag[i] == tag && back > 0 && back <= P_TEXT_SEQ_WINDOW) return text.code[i];
    }
    return -1;
}

}  // namespace bin
