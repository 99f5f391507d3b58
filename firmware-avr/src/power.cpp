#include "power.h"

#include <avr/pgmspace.h>
#include <math.h>
#include <stdlib.h>

#include "cal.h"

static float rim_f[MOTORS][3];  // RIM_Q in float, converted once

void rim_init() {
    for (uint8_t i = 0; i < MOTORS; i++)
        for (uint8_t j = 0; j < 3; j++) rim_f[i][j] = (int16_t)pgm_read_word(&RIM_Q[i][j]) * (1.0f / (1L << RIM_SHIFT));
}

float rim(uint8_t i, uint8_t j) { return rim_f[i][j]; }

// Angle (0..90 degrees) between a course and the nearest of K_l's fold axes (calibration.py fold_course):
// the idle axes on omni wheels, the body's x axis on a mecanum base.
#if !FEATURE_REACH
static
#endif
    float
    fold_course(float course) {
    float best = 90.0f;
    for (uint8_t a = 0; a < KL_AXES; a++) {
        // course in [-180, 180], axis in [0, 180): (course - axis) mod 180 without fmodf
        float d = course - (int16_t)pgm_read_word(&KL_AXES_CDEG[a]) * 0.01f;
        while (d < 0) d += 180.0f;
        while (d >= 180.0f) d -= 180.0f;
        if (d > 90.0f) d = 180.0f - d;
        if (d < best) best = d;
    }
    return best;
}

void PowerModel::wheel_speeds(float vx, float vy, float w, float *out) {
    for (uint8_t i = 0; i < MOTORS; i++) out[i] = (rim(i, 0) * vx + rim(i, 1) * vy + rim(i, 2) * w) / pgm_read_float(&WHEEL_RADIUS_M[i]);
}

uint8_t PowerModel::compute(float vx, float vy, float w, bool rotate, int16_t *out, float v) {
    float k = cal_k();
    float tr_max = 0, rot_max = 0;
    // each wheel's rim speed of the translation in raw[i], of the rotation in base[i], until the
    // powers take their place: computed once, not again for the powers
    for (uint8_t i = 0; i < MOTORS; i++) {
        float a = fabsf(raw[i] = rim(i, 0) * vx + rim(i, 1) * vy), b = fabsf(base[i] = rim(i, 2) * w);
        if (a > tr_max) tr_max = a;
        if (b > rot_max) rot_max = b;
    }
    float f_tr = 0, f_rot = 0;
    ux = uy = 0;
    if (tr_max > 0) {
        if (v < 0) v = sqrtf(vx * vx + vy * vy);
        ux = vx / v;
        uy = vy / v;
        f_tr = k * cal_kl(k * tr_max, fold_course(atan2f(vy, vx) * (180.0f / (float)M_PI)));
    }
    if (rot_max > 0) f_rot = k * (rotate ? cal_kr(k * rot_max) : cal_kt(k * rot_max));
    float peak = 0;
    for (uint8_t i = 0; i < MOTORS; i++) {
        float t = raw[i], r = base[i];
        float p = cal_motor_power(i, f_tr * t + f_rot * r, t + r);
        raw[i] = base[i] = p;
        if (fabsf(p) > peak) peak = fabsf(p);
    }
    return finish(peak, out);
}

bool PowerModel::drags() {
    if ((ux == 0 && uy == 0) || !cal_any_roller_drag()) return false;
    for (uint8_t i = 0; i < MOTORS; i++)
        if (pgm_read_float(&ROLLER_PITCH[i]) > 0 && (cal_roller(0, i) != 0 || cal_roller(1, i) != 0)) return true;
    return false;
}

// The rollers' drag at the wheels' encoder counts, made up by every wheel in proportion to its share
// of the travel (power.py PowerModel.drag).
uint8_t PowerModel::drag(const int32_t *counts, int16_t *out) {
    float total = 0, busiest = 0;
    for (uint8_t i = 0; i < MOTORS; i++) {
        float pitch = pgm_read_float(&ROLLER_PITCH[i]);
        float share = fabsf(pgm_read_float(&ROLLER_DIR[i][0]) * ux + pgm_read_float(&ROLLER_DIR[i][1]) * uy);
        if (pitch > 0 && share != 0) {
            float c = counts[i];
            float phase = 6.2831853f * (c - floorf(c / pitch) * pitch) / pitch;
            total += share * (cal_roller(0, i) * cosf(phase) + cal_roller(1, i) * sinf(phase));
        }
        float r = fabsf(rim(i, 0) * ux + rim(i, 1) * uy);
        if (r > busiest) busiest = r;
    }
    total *= drag_gain;
    float peak = 0;
    for (uint8_t i = 0; i < MOTORS; i++) {
        float p = base[i] + total * (rim(i, 0) * ux + rim(i, 1) * uy) / busiest;
        raw[i] = p;
        if (fabsf(p) > peak) peak = fabsf(p);
    }
    return finish(peak, out);
}

// Direction-keeping saturation (one factor for every motor), rounding, the dead band, the weak wheels.
uint8_t PowerModel::finish(float peak, int16_t *out) {
    uint8_t flags = 0;
    scale = 1.0f;
    if (peak > PWM_MAX) {
        scale = PWM_MAX / peak;
        flags = SATURATED;
        for (uint8_t i = 0; i < MOTORS; i++) raw[i] *= scale;
    }
    bool below = true, nonzero = false;
    for (uint8_t i = 0; i < MOTORS; i++) {
        long p = lroundf(raw[i]);
        if (p > PWM_MAX) p = PWM_MAX;
        else if (p < -PWM_MAX) p = -PWM_MAX;
        out[i] = p;
        if (p != 0) {
            nonzero = true;
            if (labs(p) >= POWER_MIN) below = false;
        }
    }
    if (nonzero && below && POWER_MIN > 0) {
        for (uint8_t i = 0; i < MOTORS; i++) out[i] = 0;
        flags |= DEADBAND;
    }
    for (uint8_t i = 0; i < MOTORS; i++)
        if (out[i] && abs(out[i]) < weak_floor) {
            out[i] = 0;
            flags |= WEAK;
        }
    return flags;
}
