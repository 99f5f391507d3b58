#include "cal.h"

#include <avr/eeprom.h>
#include <math.h>
#include <string.h>

struct Table {
    uint8_t n;
    Knot k[CAL_KNOTS];
};

struct Store {
    uint16_t magic;
    int16_t k;
    Table kt, kr, coast;
    uint8_t curves;
    uint8_t course[CAL_CURVES];  // degrees, 0..P_CAL_COURSE_MAX
    Table kl[CAL_CURVES];
    int16_t offset[MOTORS], rcos[MOTORS], rsin[MOTORS], speed[MOTORS];
    Table gain[MOTORS];
#if FEATURE_REACH
    Table reach;  // knots {folded course degrees, cm/s}
#endif
};
static_assert(sizeof(Store) <= E2END + 1, "calibration tables exceed the EEPROM");

static Store EEMEM ee;
// tells this robot's defaults apart from another build's tables, and this layout (0xCA11: speed terms,
// byte courses) from an older one
// (and, on the Mega, the layout with the reach from the one without)
static const uint16_t MAGIC = 0xCA11 ^ (MOTORS << 8) ^ DEFAULT_K ^ (FEATURE_REACH << 15);

#define EE(field) (&ee.field)

// The next table of the generated defaults (DEFAULT_KNOTS, DEFAULT_N: K_t, K_r, coast, the K_l
// curves, the gains, in that order), its knots only.
static void load_table(Table *dst, uint8_t &table, const Knot *&src) {
    Table t;
    t.n = pgm_read_byte(&DEFAULT_N[table++]);
    memcpy_P(t.k, src, t.n * sizeof(Knot));
    src += t.n;
    eeprom_update_block(&t, dst, 1 + t.n * sizeof(Knot));
}

// The intercept of p K_l(p) through the two lowest knots, x0 x1 (y0 - y1) / (x1 - x0), the smallest
// over the curves (calibration.py start_power), rounded up: a whole power is below it when below this.
static int16_t start_power() {
    float low = 1e30f;  // there is always a curve (CAL,12,-2 keeps one)
    for (uint8_t c = eeprom_read_byte(EE(curves)); c-- > 0;) {
        struct {
            uint8_t n;
            Knot k[2];
        } t;
        eeprom_read_block(&t, EE(kl[c]), sizeof t);
        if (t.n < 2) return 0;
        float a = (float)((int32_t)t.k[0].x * t.k[1].x) * (t.k[0].y - t.k[1].y) / (t.k[1].x - t.k[0].x);
        if (a < low) low = a;
    }
    return low > 0 ? (int16_t)ceilf(low * 0.001f) : 0;
}

// Shortcuts for the tables' reset values, refreshed after every CAL: the motor map is the identity
// (offsets 0, every gain knot 1.0, speed terms 0) and no roller drag coefficient is set; and
// the start power, computed after every CAL rather than on every open-loop VEL
static bool map_identity, no_roller_drag;
static int16_t start_power_cached;

int16_t cal_start_power() { return start_power_cached; }

static void refresh_shortcuts() {
    start_power_cached = start_power();
    map_identity = no_roller_drag = true;
    for (uint8_t i = 0; i < MOTORS; i++) {
        if (eeprom_read_word((const uint16_t *)EE(offset[i])) || eeprom_read_word((const uint16_t *)EE(speed[i])))
            map_identity = false;
        if (eeprom_read_word((const uint16_t *)EE(rcos[i])) || eeprom_read_word((const uint16_t *)EE(rsin[i])))
            no_roller_drag = false;
        uint8_t n = eeprom_read_byte(EE(gain[i].n));
        for (uint8_t k = 0; k < n; k++)
            if (eeprom_read_word((const uint16_t *)EE(gain[i].k[k].y)) != P_CAL_SCALE) map_identity = false;
    }
}

bool cal_any_roller_drag() { return !no_roller_drag; }

static void load_defaults();

void cal_init() {
    if (eeprom_read_word(EE(magic)) != MAGIC) load_defaults();
    refresh_shortcuts();
}

static void load_defaults() {
    uint8_t table = 0;
    const Knot *src = DEFAULT_KNOTS;
    eeprom_update_word((uint16_t *)EE(k), DEFAULT_K);
    load_table(EE(kt), table, src);
    load_table(EE(kr), table, src);
    load_table(EE(coast), table, src);
    eeprom_update_byte(EE(curves), DEFAULT_KL_CURVES);
    for (uint8_t c = 0; c < DEFAULT_KL_CURVES; c++) {
        eeprom_update_byte(EE(course[c]), pgm_read_byte(&DEFAULT_KL_COURSE[c]));
        load_table(EE(kl[c]), table, src);
    }
    for (uint8_t i = 0; i < MOTORS; i++) {
        eeprom_update_word((uint16_t *)EE(offset[i]), pgm_read_word(&DEFAULT_OFFSET[i]));
        eeprom_update_word((uint16_t *)EE(rcos[i]), pgm_read_word(&DEFAULT_ROLLER_COS[i]));
        eeprom_update_word((uint16_t *)EE(rsin[i]), pgm_read_word(&DEFAULT_ROLLER_SIN[i]));
        eeprom_update_word((uint16_t *)EE(speed[i]), pgm_read_word(&DEFAULT_SPEED[i]));
        load_table(EE(gain[i]), table, src);
    }
#if FEATURE_REACH
    Table t;
    t.n = DEFAULT_REACH_N;
    memcpy_P(t.k, DEFAULT_REACH, sizeof DEFAULT_REACH);
    eeprom_update_block(&t, EE(reach), 1 + sizeof DEFAULT_REACH);
#endif
    eeprom_update_word(EE(magic), MAGIC);
}

static inline int16_t rd16(const int16_t *p) { return (int16_t)eeprom_read_word((const uint16_t *)p); }

// Piecewise-linear y(x) / 1000, held constant outside the knots. The knots are integers, so the
// segment is found with integer compares (x <= x1 exactly when ceil(x) <= x1) and only its two
// knots are converted to float.
static float interp(const Table *t, float x) {
    uint8_t n = eeprom_read_byte(&t->n);
    int16_t x0 = rd16(&t->k[0].x);
    if (n <= 1 || x <= x0) return rd16(&t->k[0].y) * 0.001f;
    float c = ceilf(x);
    int16_t cx = c > 32767.0f ? 32767 : (int16_t)c;
    for (uint8_t i = 1; i < n; i++) {
        int16_t x1 = rd16(&t->k[i].x);
        if (cx <= x1) {
            float y0 = rd16(&t->k[i - 1].y), y1 = rd16(&t->k[i].y);
            return (y0 + (x - x0) * (y1 - y0) / (x1 - x0)) * 0.001f;
        }
        x0 = x1;
    }
    return rd16(&t->k[n - 1].y) * 0.001f;
}

float cal_k() { return rd16(EE(k)) * 0.1f; }
float cal_kt(float p) { return interp(EE(kt), p); }
float cal_kr(float p) { return interp(EE(kr), p); }
float cal_coast(float v) { return interp(EE(coast), v); }
#if FEATURE_REACH
int16_t cal_reach(float folded) { return interp(EE(reach), folded) * 1000.0f; }  // knots in cm/s, not x 1000
#endif
float cal_roller(uint8_t which, uint8_t i) { return rd16(which ? EE(rsin[i]) : EE(rcos[i])) * 0.1f; }

float cal_kl(float power, float folded) {
    uint8_t n = eeprom_read_byte(EE(curves));
    if (n == 1 || folded <= eeprom_read_byte(EE(course[0]))) return interp(EE(kl[0]), power);
    for (uint8_t i = 1; i < n; i++) {
        float c1 = eeprom_read_byte(EE(course[i]));
        if (folded <= c1) {
            float c0 = eeprom_read_byte(EE(course[i - 1]));
            float a = interp(EE(kl[i - 1]), power), b = interp(EE(kl[i]), power);
            return a + (folded - c0) * (b - a) / (c1 - c0);
        }
    }
    return interp(EE(kl[n - 1]), power);
}

// sign(a) (offset + gain(|a|) |a|) + speed u, never against a (calibration.py motor_power)
float cal_motor_power(uint8_t i, float a, float u) {
    float m = a < 0 ? -a : a;
    if (map_identity || m == 0.0f || i >= MOTORS) return a;
    if (a < 0) u = -u;
    float p = (rd16(EE(offset[i])) * (m < 1.0f ? m : 1.0f) + rd16(EE(speed[i])) * u) * 0.1f + interp(EE(gain[i]), m) * m;
    if (p < 0) p = 0;
    return a > 0 ? p : -p;
}

// Writes knot `index` (dropping the knots after it); the x values must increase strictly.
static bool write_knot(Table *t, int16_t index, int16_t x, int16_t y) {
    uint8_t n = eeprom_read_byte(&t->n);
    if (index < 0 || index > n || index >= CAL_KNOTS) return false;
    if (index > 0 && x <= rd16(&t->k[index - 1].x)) return false;
    eeprom_update_word((uint16_t *)&t->k[index].x, x);
    eeprom_update_word((uint16_t *)&t->k[index].y, y);
    eeprom_update_byte(&t->n, index + 1);
    return true;
}

static void set_table_identity(Table *t) {
    eeprom_update_word((uint16_t *)&t->k[0].x, 0);
    eeprom_update_word((uint16_t *)&t->k[0].y, P_CAL_SCALE);
    eeprom_update_byte(&t->n, 1);
}

static bool write(int16_t table, int16_t index, int16_t x, int16_t y);

bool cal_write(int16_t table, int16_t index, int16_t x, int16_t y) {
    bool ok = write(table, index, x, y);
    if (ok) refresh_shortcuts();
    return ok;
}

// The checks and conversions of firmware/controller.py `_cal` and calibration.py `set_knot`.
static bool write(int16_t table, int16_t index, int16_t x, int16_t y) {
    if (table == P_CAL_K) {
        if (index != 0 || x != 0 || y <= 0) return false;
        eeprom_update_word((uint16_t *)EE(k), y);
        return true;
    }
    if (table == P_CAL_ROLLER_COS || table == P_CAL_ROLLER_SIN || table == P_CAL_SPEED) {
        if (index < 0 || index >= MOTORS || x != 0) return false;
        int16_t *field = table == P_CAL_ROLLER_COS ? EE(rcos[index]) : table == P_CAL_ROLLER_SIN ? EE(rsin[index]) : EE(speed[index]);
        eeprom_update_word((uint16_t *)field, y);
        return true;
    }
    if (table == P_CAL_ROLLER_COAST) return x >= 0 && write_knot(EE(coast), index, x, y);
#if FEATURE_REACH
    if (table == P_CAL_REACH) return x >= 0 && x <= P_CAL_COURSE_MAX && y >= 0 && write_knot(EE(reach), index, x, y);
#endif
    if (x < 0 || y < 0) return false;
    if (table == P_CAL_OFFSET) {
        if (index < 0 || index >= MOTORS || x != 0) return false;
        eeprom_update_word((uint16_t *)EE(offset[index]), y);
        return true;
    }
    if ((table >= P_CAL_KL + P_CAL_KL_CURVES && table < P_CAL_GAIN) || table >= P_CAL_GAIN + P_CAL_MOTORS)
        return false;
    if (table == P_CAL_KT) return write_knot(EE(kt), index, x, y);
    if (table == P_CAL_KR) return write_knot(EE(kr), index, x, y);
    if (table >= P_CAL_GAIN) {
        int16_t i = table - P_CAL_GAIN;
        if (i >= MOTORS || y <= 0) return false;
        return write_knot(EE(gain[i]), index, x, y);
    }
    int16_t k = table - P_CAL_KL;
    uint8_t n = eeprom_read_byte(EE(curves));
    if (index == P_CAL_KL_DROP) {
        if (k < 1 || k > n || x != 0) return false;
        eeprom_update_byte(EE(curves), k);
        return true;
    }
    if (k < 0 || k > n || (k == n && index != -1)) return false;
    if (index == -1) {
        if (x > P_CAL_COURSE_MAX || (k > 0 && x <= eeprom_read_byte(EE(course[k - 1]))) ||
            (k + 1 < n && x >= eeprom_read_byte(EE(course[k + 1]))))
            return false;
        eeprom_update_byte(EE(course[k]), x);
        if (k == n) {
            set_table_identity(EE(kl[k]));
            eeprom_update_byte(EE(curves), n + 1);
        }
        return true;
    }
    return write_knot(EE(kl[k]), index, x, y);
}
