#include "landing.h"

#if FEATURE_LANDING
#include <avr/pgmspace.h>
#include <math.h>

static float per_rad(uint8_t i) { return pgm_read_word(&ENCODER_CPR[i]) * (1.0f / 6.2831853f); }

void Landing::init() {
    for (uint8_t k = 0; k < 4; k++) slip[k] = pgm_read_float(&DEFAULT_SLIP[k]);
}

bool Landing::set_slip(int16_t index, int16_t y) {
    if (index == 0 && y >= 0) {
        slip[0] = y * 1e-5f;
    } else if (index == 1 && y >= 0) {
        slip[1] = (float)y / P_CAL_SLIP_SCALE;
    } else if (index == 2 && P_CAL_SLIP_SCALE / 2 < y && y < 2 * P_CAL_SLIP_SCALE) {
        slip[2] = (float)y / P_CAL_SLIP_SCALE;
    } else if (index == 3 && y >= 0) {
        slip[3] = y * 1e-6f;
    } else {
        return false;
    }
    return true;
}

// After a landed motion of the same kind (dt_us after its last update) the plan carries on, and so
// does what it went past its end (or short of it), projected on this motion's direction; otherwise
// the plan starts at the body's speed along this motion from the wheels' (landing.py `start`).
void Landing::start(const int32_t *counts, const float *t, bool rot, float g, float nom, const float *wheels,
                    int32_t dt_us) {
    float vx = t[0], vy = t[1], vw = rot ? t[2] : 0;
    float carry = 0;
    if (active && rot == rotate) {
        advance(counts, dt_us, speed);
        float dot = vx * ux + vy * uy + vw * uw;
        if (dot > 0) carry = left() * dot;
    }
    for (uint8_t k = 0; k < 3; k++) twist[k] = t[k];
    for (uint8_t i = 0; i < MOTORS; i++) {
        share[i] = pgm_read_float(&TRAVEL[0][i]) * vx + pgm_read_float(&TRAVEL[1][i]) * vy +
                   pgm_read_float(&TURN[i]) * vw;
        last[i] = counts[i];
    }
    if (!active || rot != rotate) {
        float v = 0;
        if (wheels)
            for (uint8_t i = 0; i < MOTORS; i++) v += share[i] * per_rad(i) * wheels[i];
        speed = v;
        plan = v > 0 ? v : 0;
        rate = 0;
    }
    ux = vx;
    uy = vy;
    uw = vw;
    rotate = rot;
    goal = g + carry;
    done = 0;
    nominal = nom;
    active = true;
}

void Landing::update(const int32_t *counts, int32_t dt_us) {
    if (dt_us > 0) speed = advance(counts, dt_us, 0) * 1e6f / dt_us;
}

// The travel to `counts` over dt_us, less the creep at the speed v along the motion (0: this step's).
float Landing::advance(const int32_t *counts, int32_t dt_us, float v) {
    float step = 0;
    for (uint8_t i = 0; i < MOTORS; i++) {
        step += share[i] * (counts[i] - last[i]);
        last[i] = counts[i];
    }
    float dt = dt_us * 1e-6f;
    step *= slip[2];
    if (dt > 0) step -= creep(v != 0 ? v : step / dt) * dt;
    done += step;
    return step;
}

float Landing::creep(float v) {
    float over[MOTORS];
    if (!overturn(twist[0] * v, twist[1] * v, twist[2] * v, over)) return 0;
    float c = 0;
    for (uint8_t k = 0; k < MOTORS; k++) c += share[k] * per_rad(k) * over[k];
    return c;
}

// Each roller row's drag, roll tanh(rolling / ROLL_EPS) + combined sin(2 beta) rolling, shared out
// over the wheels as over-turn (CREEP_MIX); the drag creeps more under a MOVE's ramp (ramp rate^2);
// false without creep coefficients.
bool Landing::overturn(float q0, float q1, float q2, float *out) {
    float roll = slip[0], comb = slip[1];
    if (!rotate) roll += slip[3] * rate * rate;
    if (roll == 0 && comb == 0) return false;
    float term[MOTORS];
    for (uint8_t j = 0; j < MOTORS; j++) {
        float rolling = pgm_read_float(&CREEP_ROLL[j][0]) * q0 + pgm_read_float(&CREEP_ROLL[j][1]) * q1 +
                        pgm_read_float(&CREEP_ROLL[j][2]) * q2;
        float rim = pgm_read_float(&CREEP_RIM[j][0]) * q0 + pgm_read_float(&CREEP_RIM[j][1]) * q1 +
                    pgm_read_float(&CREEP_RIM[j][2]) * q2;
        float both = rim * rim + rolling * rolling;
        float t = roll * tanhf(rolling / LAND_ROLL_EPS);
        if (both > 1e-12f) t += comb * 2.0f * fabsf(rim) * fabsf(rolling) / both * rolling;
        term[j] = t;
    }
    for (uint8_t k = 0; k < MOTORS; k++) {
        float o = 0;
        for (uint8_t j = 0; j < MOTORS; j++) o += pgm_read_float(&CREEP_MIX[k][j]) * term[j];
        out[k] = o;
    }
    return true;
}

float Landing::braking() const {
    float a = rotate ? LAND_ACCEL_W : LAND_ACCEL;
    float v = speed > nominal ? speed : nominal;
    return v * v / (2.0f * a) + v * LAND_LAG_S;
}

float Landing::replan(float rest_m, float v_exit, int32_t dt_us) {
    float a = rotate ? LAND_ACCEL_W : LAND_ACCEL;
    float room = left() + rest_m - (speed > 0 ? speed : 0) * LAND_LAG_S;
    float v = room > 0 ? sqrtf(v_exit * v_exit + 2.0f * a * room) : v_exit;
    float up = plan + a * dt_us * 1e-6f;
    if (up < v) v = up;
    if (nominal < v) v = nominal;
    float least = rotate ? LAND_CRAWL_W : LAND_CRAWL;
    if (v < least) v = least < nominal ? least : nominal;
    rate = dt_us > 0 ? (v - plan) * 1e6f / dt_us : 0;
    plan = v;
    return v / nominal;
}

int32_t Landing::time_left(int32_t period_us) const {
    float l = left(), v = speed;
    if (l <= 0 || (v <= 0 && l < (rotate ? LAND_TOLERANCE_W : LAND_TOLERANCE))) return 0;
    if (v > 0 && l < v * period_us * 1e-6f) return (int32_t)(l / v * 1e6f);
    return LAND_FAR_US;
}
#endif
