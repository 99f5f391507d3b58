// The sonar stop's guard (firmware/safety.py SonarGuard, one sonar).
#include "safety.h"

#include <avr/pgmspace.h>
#include <math.h>

SonarGuard guard = {0, 0, -1.0f, -1.0f, 0.0f, false, false, 0, 0};

// Travel along the sonar's axis before the footprint could touch a straight wall whose nearest
// point in the cone is r away, for walls met at up to 60 degrees from square, less the lead.
static float travel_room(float r) {
    if (r < 0) return -1.0f;
    float room = r;
    for (uint8_t k = 0; k < GUARD_STEPS; k++) {
        float c = pgm_read_float(&GUARD_COS[k]), s = pgm_read_float(&GUARD_SIN[k]);
        float seen = (k + 1) * GUARD_STEP > GUARD_HALF ? r * (c * cosf(GUARD_HALF) + s * sinf(GUARD_HALF)) : r;
        float m = (seen - GUARD_WIDTH * s) / c;
        if (m < room) room = m;
    }
    room -= GUARD_LEAD;
    return room > 0 ? room : 0.0f;
}

void SonarGuard::reading(int16_t cm) {
    if (cm >= 0) {
        range = cm;
        missed = false;
    } else if (range >= 0 && !missed) {  // first miss: the last range, less the travel since
        range -= closing * period * 0.001f;
        if (range < 0) range = 0;
        missed = true;
    } else {
        range = -1.0f;
    }
    room = travel_room(range);
}

void SonarGuard::clear() {
    range = room = -1.0f;
    missed = false;
}

bool SonarGuard::below_stop() const { return armed() && range >= 0 && range < stop; }

static float angle(float ux, float uy) {
    float d = ux * GUARD_AX + uy * GUARD_AY;
    if (d >= 1.0f) return 0.0f;
    if (d <= -1.0f) return (float)M_PI;
    return acosf(d);
}

bool SonarGuard::covers(float vx, float vy) const {
    if (!armed()) return true;
    float v = sqrtf(vx * vx + vy * vy);
    return v > 0 && angle(vx / v, vy / v) <= GUARD_HALF;
}

float SonarGuard::factor(float vx, float vy) {
    flags = code = 0;
    if (vx == 0 && vy == 0) return 1.0f;
    closing = 0;
    if (!armed()) return 1.0f;  // nothing limits the speed: no square root to take
    vx *= 100.0f;                // cm/s from here on
    vy *= 100.0f;
    float v = sqrtf(vx * vx + vy * vy);
    float allowed = v;
    bool covered = false;
    {
        float off = angle(vx / v, vy / v) - GUARD_HALF, c = 0;
        if (off <= 0) {
            covered = true;
            c = 1.0f;
        } else if (off < (float)(M_PI / 2)) {
            c = cosf(off);
        }
        if (c > 0) {  // not moving away from all the cone sees
            closing = v * c;
            if (room >= 0) {
                float d = room - stop, m = 0;
                if (d > 0) {
                    float t = (period + GUARD_LOOP_MS) * 0.001f + 2.0f * range / GUARD_SOUND_CMS;
                    m = GUARD_DECEL * (sqrtf(t * t + 2.0f * d / GUARD_DECEL) - t);
                }
                if (m / c < allowed) allowed = m / c;
            }
        }
        if (!covered) {
            if (refuse) {
                code = P_E_UNCOVERED;
                return 0;
            }
            if (GUARD_UNCOVERED < v) {
                flags |= UNCOVERED;
                if (GUARD_UNCOVERED < allowed) allowed = GUARD_UNCOVERED;
            }
        }
    }
    if (allowed >= v) return 1.0f;
    float floor = v < GUARD_V_MIN ? v : GUARD_V_MIN;
    if (allowed < floor) {
        code = P_W_SONAR_STOP;
        return 0;
    }
    if (!(flags & UNCOVERED) || allowed < GUARD_UNCOVERED) flags |= LIMITED;
    return allowed / v;
}
