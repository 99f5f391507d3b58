// omnibot's motor controller for the Arduino UNO: the text and binary protocols of docs/protocol.md.
// One main-loop pass: advance the clock, the motion timeline, read and answer every complete
// command, run the sonar and its guard, send TEL when due; then sleep until the next interrupt
// (1 ms at most).
#include <avr/pgmspace.h>
#include <math.h>
#include <stdlib.h>

#include "binlink.h"
#include "cal.h"
#include "hal.h"
#include "checks.h"
#include "motion.h"
#include "safety.h"
#include "textout.h"

static char line[LINE_MAX + 1];
static uint8_t line_len;
// four flags in one byte (static RAM is at its limit): the line overflowed, the sonar stop is
// latched, MODE bit 2 (frames both ways), a sonar reading is waiting
static struct {
    bool overflow : 1;
    bool latched : 1;
    bool binary : 1;
    bool sonar_pending : 1;
} st;
static uint32_t now_ms;
static uint32_t us_part;
static uint32_t last_ticks;
static uint8_t tick_half;
// sonar (sonar.py, one sonar; its period and STOP are the guard's)
static int16_t sonar_low, sonar_high, sonar_last = -1;
static uint32_t sonar_next, sonar_started;
// battery (battery.py): f is 64 times the filtered ADC count (time constant 64 readings);
// level 0 ok, 1 warned (WARN 19), 2 limited (WARN 20, motion.cpp caps the power), 3 stopped (WARN 43)
static uint16_t batt_f;
static uint8_t batt_below;
uint8_t batt_level;
// telemetry
static uint16_t tel_period;
static uint8_t tel_mask;
static uint32_t tel_next;

// ------------------------------------------------------------------ replies and events

static PGM_P code_text(uint8_t code) {
    for (uint8_t i = 0; i < CODE_TEXT_COUNT; i++)
        if (pgm_read_byte(&CODE_TEXTS[i].code) == code) return (PGM_P)pgm_read_ptr(&CODE_TEXTS[i].text);
#if FEATURE_PROGRESS || FEATURE_REACH
    for (uint8_t i = 0; i < FEATURE_CODE_TEXT_COUNT; i++)
        if (pgm_read_byte(&FEATURE_CODE_TEXTS[i].code) == code)
            return (PGM_P)pgm_read_ptr(&FEATURE_CODE_TEXTS[i].text);
#endif
    return PSTR("");
}

static void coded(PGM_P keyword, uint8_t code) {
    out_P(keyword);
    comma_i(code);
    out_c(',');
    out_P(code_text(code));
}
static void ok() {
    if (st.binary) {
        bin::begin(T_OK, bin::seq());
        bin::send_reply();
        return;
    }
    bin::text_result(0);
    out_P(PSTR("OK"));
    end_reply();
}
// Binary ERROR and WARN frames carry no text: the code table's text applies (docs/protocol.md).
static void error(uint8_t code) {
    if (st.binary) {
        bin::begin(T_ERROR, bin::seq());
        bin::put(code);
        bin::send_reply();
        return;
    }
    bin::text_result(code);
    coded(PSTR("ERROR"), code);
    end_reply();
}
void on_warn(uint8_t code) {
    if (st.binary) return bin::event(T_WARN, code, 0, 1);
    coded(PSTR("WARN"), code);
    end_line();
}
void on_idle() {
    if (st.binary) return bin::event(T_IDLE, 0, 0, 0);
    out_P(PSTR("IDLE"));
    end_line();
}
uint32_t controller_ms() { return now_ms; }

static uint8_t state() {
    if (batt_level == 3) return P_STATE_BATTERY;
    if (st.latched) return P_STATE_ESTOP;
    return ex.moving() ? P_STATE_MOVING : P_STATE_IDLE;
}

#if FEATURE_VEL_ACCEL
static uint8_t hello_version = P_PROTOCOL_VERSION;  // the last HELLO's: the highest version both speak
#else
#define hello_version P_PROTOCOL_VERSION
#endif

static void hello() {
    if (st.binary) {
        bin::begin(T_HELLO_REPLY, bin::seq());
        bin::put(hello_version);
        bin::put(MOTORS);
        bin::put(bin::window());
        bin::text_P(PSTR(ROBOT_NAME));
        bin::send_reply();
        return;
    }
    out_P(PSTR("HELLO,"));
    out_i(hello_version);
    out_P(PSTR("," ROBOT_NAME));
    comma_i(MOTORS);
    end_reply();
}

static uint8_t mode_bits() {
    return ex.mode | (st.binary ? P_MODE_BINARY : 0) | (guard.refuse ? P_MODE_REFUSE_UNCOVERED : 0);
}

static void status() {
    if (st.binary) {
        bin::begin(T_STATUS_REPLY, bin::seq());
        bin::put(state());
        bin::put(ex.queue.count);
        bin::put(QUEUE_CAPACITY);
        bin::put(mode_bits());
        for (uint8_t i = 0; i < MOTORS; i++) bin::put(ex.powers[i]);
        for (uint8_t i = 0; i < 4; i++) bin::put(ex.remembered[i]);
        bin::send_reply();
        return;
    }
    out_P(PSTR("STATUS,"));
    out_i(state());
    comma_i(ex.queue.count);
    comma_i(QUEUE_CAPACITY);
    comma_i(mode_bits());
    out_P(PSTR(";POWER"));
    for (uint8_t i = 0; i < MOTORS; i++) comma_i(ex.powers[i]);
    out_P(PSTR(";MOVE"));
    for (uint8_t i = 0; i < 4; i++) comma_i(ex.remembered[i]);
    end_reply();
}

static void field(int32_t v) {
    if (st.binary) bin::put(v);
    else comma_i(v);
}

static void telemetry() {
    if (st.binary) {
        bin::begin(T_TEL, 0);
        bin::put_u32(now_ms);
    } else {
        out_P(PSTR("TEL,"));
        out_u(now_ms);
    }
    field(tel_mask);
    if (tel_mask & P_TEL_POWER) {
        field(MOTORS);
        for (uint8_t i = 0; i < MOTORS; i++) field(ex.powers[i]);
    }
    if (tel_mask & P_TEL_ENCODERS) {
        field(HAS_ENCODERS ? MOTORS : 0);
        for (uint8_t i = 0; i < (HAS_ENCODERS ? MOTORS : 0); i++) field(encoder_count(i));
    }
    if (tel_mask & P_TEL_TRACKING) field(0);  // no tracking wheels on the UNO wiring
    if (tel_mask & P_TEL_GYRO) field(0);      // no gyro on the UNO wiring
    if (tel_mask & P_TEL_HEADING) field(0);
    if (tel_mask & P_TEL_BATTERY) field(battery_mv());
    if (tel_mask & P_TEL_QUEUE) {
        field(state());
        field(ex.queue.count);
    }
    if (tel_mask & P_TEL_SONAR) {
        field(SONARS);
        if (SONARS) field(sonar_last);
    }
    if (st.binary) bin::send_plain();
    else end_line();
}

// ------------------------------------------------------------------ commands

// Sonar emergency stop: motors off and braked, queue cleared, WARN 13, latched until STOP.
static void emergency_stop() {
    ex.stop();
    ex.brake();
    st.latched = true;
    on_warn(P_W_SONAR_STOP);
    on_idle();
}

// Reports a motion the guard stopped (ex.halt): the emergency stop, or an uncovered one.
static void check_halt() {
    uint8_t code = ex.halt;
    if (!code) return;
    ex.halt = 0;
    if (code == P_W_SONAR_STOP) {
        emergency_stop();
    } else {
        on_warn(P_W_UNCOVERED_STOP);
        on_idle();
    }
}

// The guard's inputs changed (a reading, SONAR, MODE): limit the running travel anew.
static void relimit() {
    ex.relimit();
    check_halt();
}

// A MOVE or VEL travels where the armed sonar looks (or does not travel); other commands: true.
static bool covered(uint8_t kw, const int16_t *p) {
    if (kw == K_MOVE) {
        if (p[0] == 0) return true;
        float a = p[2] * (float)(M_PI / 180), s = (p[0] > 0) == (p[1] > 0) ? 1.0f : -1.0f;
        return guard.covers(s * cosf(a), s * sinf(a));
    }
    if (kw == K_VEL && (p[0] || p[1])) return guard.covers(p[0], p[1]);
    return true;
}

static void execute(uint8_t kw, int16_t *p, uint8_t n, uint8_t lo, uint8_t hi) {
    uint8_t code = check(kw, p, n, lo, hi);
    bool motion = kw == K_MOVE || kw == K_ROTATE || kw == K_DELTA || kw == K_POWER || kw == K_VEL;
    if (!code && motion) {
        if (batt_level == 3) code = P_E_BATTERY;
        else if (st.latched) code = P_E_ESTOP;
    }
    if (!code && guard.refuse && !covered(kw, p)) code = P_E_UNCOVERED;
    if (code) {
        error(code);
        return;
    }
    switch (kw) {
        case K_MOVE:
        case K_ROTATE:
        case K_DELTA:
        case K_POWER:
            if (!ex.queue.push(kw, p, n)) {
                error(P_E_QUEUE_FULL);
                return;
            }
            ok();
            ex.step(0);
            check_halt();
            break;
        case K_VEL:
            ok();
#if FEATURE_VEL_ACCEL
            ex.vel(p[0], p[1], p[2], p[3], n == 5 ? p[4] : 0, n == 7 ? p + 4 : 0);
#else
            ex.vel(p[0], p[1], p[2], p[3]);
#endif
            check_halt();
            break;
        case K_STOP: {
            bool was = ex.stop();
            ex.reset_move();
            st.latched = false;
            if (batt_level == 3 && batt_f >= BATTERY_STOP + BATTERY_HYST)  // a charged pack
                batt_level = batt_f < BATTERY_LIMIT + BATTERY_HYST ? 2 : 1;
            ok();
            if (was) on_idle();
            break;
        }
        case K_STATUS:
            status();
            break;
        case K_HELLO:
#if FEATURE_VEL_ACCEL
            hello_version = P_PROTOCOL_VERSION;  // a bare HELLO: the version every host speaks
            for (uint8_t i = 0; i < n; i++)
                if (p[i] > hello_version && p[i] <= P_VERSION_MAX) hello_version = p[i];
#endif
            hello();
            break;
        case K_MODE: {
            ok();  // in the mode the command came in
            guard.refuse = p[0] & P_MODE_REFUSE_UNCOVERED;
            ex.set_mode(p[0] & ~(P_MODE_BINARY | P_MODE_REFUSE_UNCOVERED));
            relimit();
            bool b = p[0] & P_MODE_BINARY;
            if (b != st.binary) {  // from the next byte on, both ways
                st.binary = b;
                bin::reset();
                bin::text_reset();
                line_len = 0;
                st.overflow = false;
            }
            break;
        }
        case K_SONAR:
            guard.period = p[1];
            sonar_low = p[2];
            sonar_high = p[3];
            guard.stop = p[4];
            sonar_next = now_ms;
            guard.clear();
            ok();
            relimit();
            break;
        case K_TELEM:
            tel_period = p[0];
            tel_mask = p[1];
            tel_next = now_ms;
            ok();
            break;
        case K_CAL:
#if FEATURE_LANDING
            if (p[0] == P_CAL_SLIP) {  // the floor's creep: a landing's travel (RAM, as on MicroPython)
                if (p[2] == 0 && ex.landing.set_slip(p[1], p[3])) ok();
                else error(P_E_CALIBRATION);
                break;
            }
#endif
            if (cal_write(p[0], p[1], p[2], p[3])) ok();
            else error(P_E_CALIBRATION);
            break;
        default:
            error(P_E_INTERNAL);
    }
}

static bool blank(char c) { return c == ' ' || c == '\t'; }  // VT, FF: part of their field
static bool digit(char c) { return c >= '0' && c <= '9'; }
static uint8_t upper(char c) { return c >= 'a' && c <= 'z' ? c - 32 : c; }
static int8_t hex(char c) {
    if (digit(c)) return c - '0';
    c = upper(c);
    return c >= 'A' && c <= 'F' ? c - 'A' + 10 : -1;
}

// Parses one command's body (parser.py `parse`): the keyword's table entry into `e`, the parameters
// into `p` and `n`. Returns 0, 255 for a blank command, or the ERROR code (23, 24, 25, 34): the
// whole command's syntax comes before any range.
static uint8_t parse(char *cmd, uint8_t len, const Keyword *&e, int16_t *p, uint8_t &n) {
    char *end = cmd + len;
    *end = ',';  // sentinel (the line buffer has room for it)
    char *field_end = cmd;
    while (*field_end != ',') field_end++;
    char *a = cmd, *b = field_end;
    while (a < b && blank(*a)) a++;
    while (b > a && blank(b[-1])) b--;
    if (a == b && field_end == end) return 255;
    e = 0;
    for (uint8_t k = 0; k < K_COUNT && !e; k++) {
        const Keyword *t = &KEYWORDS[k];
        uint8_t i = 0;
        for (; a + i < b; i++)
            if (i >= sizeof(t->name) || !a[i] || upper(a[i]) != pgm_read_byte(&t->name[i])) break;  // a NUL
        // matches no keyword (the names are NUL-padded: "STATUS\0" would have run as STATUS)
        if (a + i == b && (i == sizeof(t->name) || pgm_read_byte(&t->name[i]) == 0)) e = t;
    }
    if (!e) return P_E_UNKNOWN;
    uint8_t fields = 0;
    for (char *c = field_end; c < end; c++)
        if (*c == ',') fields++;
#if FEATURE_VEL_ACCEL
    if (fields > (pgm_read_byte(&e->id) == K_VEL ? P_VEL_PARAMS_MAX : P_PARAMS_MAX)) return P_E_PARAM_COUNT;
#else
    if (fields > P_PARAMS_MAX) return P_E_PARAM_COUNT;
#endif
    uint8_t inf_at = pgm_read_byte(&e->inf);
    bool wide = false;
    n = 0;
    for (char *c = field_end; c < end;) {
        c++;  // past the comma
        while (blank(*c)) c++;
        bool neg = false;
        if (*c == '-' || *c == '+') neg = *c++ == '-';
        int32_t v = 0;
        if (n + 1 == inf_at && upper(c[0]) == 'I' && upper(c[1]) == 'N' && upper(c[2]) == 'F') {
            v = P_INF;
            c += 3;
        } else {
            uint8_t digits = 0;
            for (; digit(*c); c++, digits++)
                if (v < 100000) v = v * 10 + (*c - '0');
            if (!digits) return P_E_NOT_INTEGER;
        }
        while (blank(*c)) c++;
        if (*c != ',') return P_E_NOT_INTEGER;
        if (neg) v = -v;
        if (v < -32768 || v > 32767) wide = true;
        p[n++] = v;
    }
    return wide ? P_E_RANGE16 : 0;
}

// Handles one text command: its "#tag" and "*check" suffix (linecheck.split; a bad check is
// ERROR 26, untagged, and nothing runs), then the body; the reply carries the command's suffix.
// With MODE bit 4 (kept in ex.mode) a command without a check is ERROR 42, untagged.
static void handle(char *cmd, uint8_t len) {
    uint8_t end = len;
    bool checked = false;
    if (len > 4 && cmd[len - 5] == '*') {
        uint16_t want = 0;
        bool all_hex = true;
        for (uint8_t i = len - 4; i < len; i++) {
            int8_t h = hex(cmd[i]);
            if (h < 0) all_hex = false;
            want = want << 4 | (h & 0xF);
        }
        if (all_hex) {
            end = len - 5;
            uint16_t crc = 0xFFFF;
            for (uint8_t i = 0; i < end; i++) crc = crc16_update(crc, cmd[i]);
            if (crc != want) return error(P_E_CHECKSUM);
            checked = true;
        }
    }
    uint8_t i = end;
    while (i > 0 && end - i <= 4 && digit(cmd[i - 1])) i--;
    uint8_t tag_at = i, tag_len = 0;
    uint16_t tag = 0;
    if (i > 0 && cmd[i - 1] == '#' && end - i >= 1 && end - i <= 4) {
        tag_len = end - i;
        end = i - 1;
        for (uint8_t k = 0; k < tag_len; k++) tag = tag * 10 + cmd[tag_at + k] - '0';
    }
    const Keyword *e;
    int16_t p[CMD_PARAMS_MAX];
    uint8_t n;
    uint8_t code = parse(cmd, end, e, p, n);
    if (code == 255) return;
    // MODE bit 4: only what a check covers runs (a line cut short by a damaged byte has none)
    if (!checked && (ex.mode & P_MODE_CHECKED_TEXT)) return error(P_E_CHECK_REQUIRED);
    ReplySuffix &r = reply_suffix;
    for (uint8_t k = 0; k < tag_len; k++) r.tag[k] = cmd[tag_at + k];
    r.tag_len = tag_len;
    r.check = checked;
    // MODE bit 5: a checked tag is a sequence number (controller.py `_in_sequence`): a duplicate
    // gets its kept reply (a query runs again), one out of order nothing; STOP, HELLO, MODE are
    // taken whatever tag was expected, HELLO starts afresh
    uint8_t id = code ? 0 : pgm_read_byte(&e->id);
    bool sequenced = checked && tag_len && (ex.mode & P_MODE_SEQUENCED_TEXT);
    uint8_t kind = 0;
    if (sequenced) {
        if (id == K_HELLO) bin::text_reset();
        kind = bin::text_classify(tag, id == K_STOP || id == K_HELLO || id == K_MODE);
    }
    int16_t kept = kind == 1 ? bin::text_kept(tag) : 255;
    bin::text_result(255);
    if (kind == 2 || kept < 0) {
    } else if (kept != 255) {
        if (kept) error(kept);
        else ok();
    } else if (code) {
        error(code);
    } else {
        execute(id, p, n, pgm_read_byte(&e->lo), pgm_read_byte(&e->hi));
    }
    if (!kind && checked && tag_len && (ex.mode & P_MODE_SEQUENCED_TEXT)) {
        if (!sequenced) {  // the MODE that set bit 5 starts the sequence with its own tag
            bin::text_reset();
            bin::text_classify(tag, true);
        }
        bin::text_remember(tag);
    }
    r.tag_len = 0;
    r.check = false;
}

// A binary command frame (controller.py `_frame`): the same checks and execution as text.
void on_frame(uint8_t type, int32_t *ints, uint8_t n) {
    const Keyword *e = 0;
    for (uint8_t k = 0; k < K_COUNT; k++)
        if (pgm_read_byte(&KEYWORDS[k].id) == type) e = &KEYWORDS[k];
    if (!e) return error(P_E_UNKNOWN);
    if (n == 255) return error(P_E_NOT_INTEGER);
#if FEATURE_VEL_ACCEL
    if (n > (type == K_VEL ? P_VEL_PARAMS_MAX : P_PARAMS_MAX)) return error(P_E_PARAM_COUNT);
#else
    if (n > P_PARAMS_MAX) return error(P_E_PARAM_COUNT);
#endif
    int16_t p[CMD_PARAMS_MAX];
    for (uint8_t i = 0; i < n; i++) {
        if (ints[i] < -32768 || ints[i] > 32767) return error(P_E_RANGE16);
        p[i] = ints[i];
    }
    execute(type, p, n, pgm_read_byte(&e->lo), pgm_read_byte(&e->hi));
}

void on_query_again(uint8_t type) {
    if (type == K_HELLO) hello();
    else status();
}

// Splits the byte stream into commands (parser.py LineSplitter).
static void feed(char c) {
    if (c == ';' || c == '\r' || c == '\n') {
        if (st.overflow) {
            st.overflow = false;
            error(P_E_TOO_LONG);
        } else if (line_len) {
            handle(line, line_len);
        }
        line_len = 0;
        return;
    }
    if (st.overflow) return;
    if (line_len == LINE_MAX) {
        st.overflow = true;
        line_len = 0;
        return;
    }
    line[line_len++] = c;
}

// ------------------------------------------------------------------ sonar (sonar.py)

static void sonar_poll() {
    if (!SONARS) return;
    if (st.sonar_pending) {
        int16_t cm = sonar_result();
        if (cm == -2) {
            if ((int32_t)(now_ms - sonar_started) < 100) return;
            cm = -1;  // no echo within 100 ms
        }
        st.sonar_pending = false;
        sonar_last = cm;
        if (guard.period == 0) return;
        if (cm >= 0 && ((sonar_low < sonar_high && sonar_low <= cm && cm <= sonar_high) ||
                        (sonar_low > sonar_high && (cm < sonar_high || cm > sonar_low)))) {
            if (st.binary) {
                bin::event(T_RANGE, 1, cm, 2);
            } else {
                out_P(PSTR("RANGE,1"));
                comma_i(cm);
                end_line();
            }
        }
        guard.reading(cm);  // the guard re-limits a travel or calls the emergency stop
        if (!ex.moving()) return;
        if (ex.travelling()) relimit();
        else if (guard.below_stop()) emergency_stop();  // ROTATE, POWER: the threshold alone
    } else if (guard.period && (int32_t)(now_ms - sonar_next) >= 0) {
        sonar_next += guard.period;
        if ((int32_t)(now_ms - sonar_next) >= 0) sonar_next = now_ms + guard.period;
        st.sonar_pending = true;
        sonar_started = now_ms;
        sonar_trigger();
    }
}

// One battery reading: levels entered after BATTERY_DELAY readings below their threshold, left above
// it plus the hysteresis; the stop latches. A pin below half the stop threshold: no battery measured.
static void battery_sample() {
    uint16_t a = battery_adc();
    if (a < (BATTERY_STOP >> 7)) return;
    batt_f = batt_f ? batt_f + a - (batt_f >> 6) : a << 6;
    uint8_t level = batt_level;
    if (level == 3) return;
    uint8_t down = batt_f < BATTERY_STOP ? 3 : batt_f < BATTERY_LIMIT ? 2 : batt_f < BATTERY_WARN ? 1 : 0;
    if (down > level) {
        if (++batt_below < BATTERY_DELAY) return;
        batt_below = 0;
        if (level < 1) on_warn(P_W_BATTERY_LOW);
        if (level < 2 && down >= 2) on_warn(P_W_BATTERY_LIMIT);
        batt_level = down;
        if (down == 3) {
            ex.stop();
            ex.brake();
            on_warn(P_W_BATTERY_STOP);
            on_idle();
        }
    } else {
        batt_below = 0;
        if (level == 2 && batt_f >= BATTERY_LIMIT + BATTERY_HYST) batt_level = 1;
        if (batt_level == 1 && batt_f >= BATTERY_WARN + BATTERY_HYST) batt_level = 0;
    }
    if (batt_level < 3) ex.apply();  // the power cap may have changed
}

static bool tel_due() {
    if (!tel_period || (int32_t)(now_ms - tel_next) < 0) return false;
    tel_next += tel_period;
    if ((int32_t)(now_ms - tel_next) >= 0) tel_next = now_ms + tel_period;
    return true;
}

// Paints the free RAM so the emulator can measure the deepest stack (docs/uno.md).
extern uint8_t __heap_start;
__attribute__((naked, used, section(".init3"))) static void paint_stack() {
    uint8_t *p = &__heap_start;
    while (p < (uint8_t *)SP - 16) *p++ = 0xAA;
}

int main() {
    hal_init();
    cal_init();
    ex.init();
    ex.set_mode(MODE_AT_RESET & (P_MODE_SIMULATION | P_MODE_CLOSED_LOOP));
    hello();
    last_ticks = hal_ticks();
    for (;;) {
        uint32_t t = hal_ticks();
        uint32_t ticks = t - last_ticks + tick_half;
        last_ticks = t;
        tick_half = ticks & 1;
        int32_t dt = ticks >> 1;
        us_part += dt;  // a pass lasts a few ms at most: subtracting beats dividing on the AVR
        bool batt_due = false;
        while (us_part >= 1000) {
            us_part -= 1000;
            now_ms++;
            if (!(now_ms % BATTERY_PERIOD_MS)) batt_due = true;
        }
        ex.step(dt);
        check_halt();
        for (int16_t c; (c = uart_read()) >= 0;) {
            if (st.binary) bin::feed(c);
            else feed(c);
        }
        sonar_poll();
        if (batt_due) battery_sample();
        if (tel_due()) telemetry();
        if (st.binary) bin::poll(now_ms);
        hal_wait_for_event();
    }
}
