// Motor powers for a body twist: seed 000's formulas (1)-(3) through the kinematics (firmware/power.py).
#pragma once
#include <stdint.h>

#include "features.h"

#define SATURATED 1
#define DEADBAND 2
#define WEAK 16  // safety.h owns 4 and 8

struct PowerModel {
    float raw[MOTORS];    // powers before rounding, after saturation
    float base[MOTORS];   // powers of compute(), before the roller drag
    float scale;          // saturation factor of the last computation (1: none)
    float drag_gain;      // the MOVE's coast factor of the roller drag
    float ux, uy;         // direction of travel of the last twist (0, 0: none)
    int16_t weak_floor;   // a wheel given less (not 0) is set to 0 (WEAK); 0: no such check

    // v: the travel speed sqrt(vx^2 + vy^2) when the caller has it (negative: computed here)
    uint8_t compute(float vx, float vy, float w, bool rotate, int16_t *out, float v = -1.0f);
    void wheel_speeds(float vx, float vy, float w, float *out);  // rad/s
    bool drags();
    uint8_t drag(const int32_t *counts, int16_t *out);
    uint8_t finish(float peak, int16_t *out);
};

void rim_init();  // at start-up
#if FEATURE_REACH
float fold_course(float course);  // degrees: 0..90 from the nearest of K_l's (and the reach's) fold axes
#endif
float rim(uint8_t i, uint8_t j);
