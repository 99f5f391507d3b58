// Closed-loop landing (firmware/landing.py), the Mega's only (FEATURE_LANDING, features.h): in MODE 2
// a finite MOVE, each DELTA repetition and a ROTATE end when the encoders say the body went its
// distance (angle), the speed planned up from rest and down to what the command queued behind keeps,
// the floor's creep (CAL table 9) taken out.
#pragma once
#include <stdint.h>

#include "features.h"

#if FEATURE_LANDING
struct Landing {
    bool active, rotate;
    float goal;     // m (rad for a ROTATE), > 0
    float done;     // travelled along the motion since it started
    float speed;    // along the motion, measured over the last update, m/s (rad/s)
    float nominal;  // the speed asked
    float plan;     // the speed planned now; 0 at rest
    float rate;     // the plan's rate of change, m/s^2 (rad/s^2)
    float ux, uy, uw;  // the motion's direction: body-frame unit vector, or the turn's sign
    float share[MOTORS];  // travel along the motion per count of each wheel
    int32_t last[MOTORS];
    float slip[4];   // roll m/s, combined, scale, ramp s^3/m (CAL table 9)
    float twist[3];  // the motion's twist per unit of its speed

    void init();
    bool set_slip(int16_t index, int16_t y);  // CAL table 9's coefficient; false: ERROR 38
    float left() const { return goal - done; }
    void rest() {  // at rest: the next plan starts at 0
        active = false;
        speed = plan = rate = 0;
    }
    // twist: per unit of speed; wheels: the speed loop's last measure (rad/s; 0 at rest)
    void start(const int32_t *counts, const float *twist, bool rotate, float goal, float nominal,
               const float *wheels, int32_t dt_us);
    void update(const int32_t *counts, int32_t dt_us);
    bool overturn(float q0, float q1, float q2, float *out);  // each wheel's creep, rad/s
    float braking() const;
    float replan(float rest, float v_exit, int32_t dt_us);  // the plan's share of nominal
    int32_t time_left(int32_t period_us) const;

  private:
    float advance(const int32_t *counts, int32_t dt_us, float v);
    float creep(float v);
};
#endif
