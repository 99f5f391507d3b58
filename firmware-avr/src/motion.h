// The command queue and the motion executor: timeline of MOVE/ROTATE/DELTA/POWER, VEL and its
// watchdog, STOP, the remembered MOVE, the mode bits, the closed wheel-speed loop, the sonar guard's
// speed limit (firmware/motion.py).
#pragma once
#include <stdint.h>

#include "features.h"
#include "landing.h"
#include "power.h"

#define NONE 0

struct Slot {
    uint8_t kind;
    int16_t p[5];
};

struct Queue {
    Slot slots[QUEUE_CAPACITY];
    uint8_t head, count;
    bool push(uint8_t kind, const int16_t *p, uint8_t n);
    const Slot &pop();
    void clear() { head = count = 0; }
};

struct Executor {
    Queue queue;
    PowerModel model;
    uint8_t kind;
    bool infinite;
    int64_t remaining;  // us of the running motion (ROTATE,30000,1 lasts 30000 s)
    int16_t powers[MOTORS];
    int16_t applied[MOTORS];
    uint8_t mode;
    int16_t remembered[4];
    int16_t delta[4];
    uint16_t reps;
    bool reps_inf;
    uint8_t warned;
    bool watchdog;
    int32_t watchdog_us;
    float twist[3];    // the twist driven (m/s, m/s, rad/s), after the guard's factor
    float nominal[4];  // the twist commanded and the roller drag's gain, before the guard
    float k;           // the guard's factor in force
    float time_scale;  // saturation and guard factor: a finite MOVE's time is stretched by 1/time_scale
    float speed;       // travel speed driven, cm/s
    int32_t coast_us;  // left of coasting (powers off) down to a speed the guard lowered
    uint8_t halt;      // the guard stopped the motion: W_SONAR_STOP or E_UNCOVERED, for the controller
    bool rot;
    bool dead;  // the last twist's powers fell in the dead band
    float ff[MOTORS], target[MOTORS];
    bool feedback, dragging;
    int32_t control_due;
    // closed loop (speedctl.py)
    float integ[MOTORS], correction[MOTORS];
    float prev_target[MOTORS];  // the targets of the last period
    uint8_t rising;             // bit i: wheel i's target stepped and it is not yet within the band
#if FEATURE_SPEEDCTL
    uint8_t rise_up, rise_down;    // bit i: wheel i rises until it reaches a target above (below) it
    uint8_t held[MOTORS];          // periods wheel i's target has not changed (up to STEADY_PERIODS)
#endif
    int32_t last_counts[MOTORS];
    int32_t acc_us;
#if FEATURE_VEL_ACCEL
    float acc[3];       // a VEL's planned body acceleration, m/s^2, m/s^2, rad/s^2
    bool acc_on;        // the VEL carries one
    bool acc_turning;   // version 4's: the wheels' part takes the turning axes' term (accel)
#endif
#if FEATURE_BRAKE
    bool braking, slewing;       // a VEL's watchdog ran out on the closed loop: down to rest
    float ref[3];                // the slewed twist driven now, m/s, m/s, rad/s
    float wheel_speed[MOTORS];   // rad/s, the speed loop's last measure
    int32_t slew_due, brake_us, brake_min_us, rest_due;
    int32_t rest_ref[MOTORS];
#endif
#if FEATURE_LANDING
    Landing landing;
    float land_scale;    // the landing's ramp: share of the asked speed driven now
    int32_t land_us;     // since the landing's last update
    int64_t deadline;    // us a landing motion may still take before it ends short
    float unit[3];       // the landing motion's twist per unit of its speed
#endif
#if FEATURE_PROGRESS
    // the MOVE progress check (progress.py): off, a MOVE running, its coast watched
    uint8_t watch;
    float share[MOTORS];  // m of travel along the MOVE's course per count of each wheel
    int32_t watch_start[MOTORS], watch_last[MOTORS];
    float watch_distance;  // m
    int32_t watch_coast_us, watch_due;
#endif

    void init();
    bool moving() const { return kind != NONE; }
    bool travelling() const {
        return (kind == K_MOVE || kind == K_DELTA || kind == K_VEL) && (nominal[0] != 0 || nominal[1] != 0);
    }
    void set_mode(uint8_t m);
    void apply();
    bool stop();
    void brake();    // after stop(): every motor braked (L298: EN high, IN1 = IN2 = 0) until the next power
    void relimit();  // the guard's inputs changed: re-drive the travel with its new factor
    void reset_move();
#if FEATURE_VEL_ACCEL
    // accel: version 3's A (cm/s^2 along the travel); body: version 4's AX, AY, AW (cm/s^2, deg/s^2)
    void vel(int16_t vx, int16_t vy, int16_t w, int16_t t_ms, int16_t accel, const int16_t *body);
#else
    void vel(int16_t vx, int16_t vy, int16_t w, int16_t t_ms);
#endif
    void step(int32_t dt_us);

  private:
    void finish();
    void start_next(int64_t carry);
    void repeat(int64_t carry);
    void move(int64_t carry);
    void rotate(int16_t a, int16_t f, int64_t carry);
    void drive(float vx, float vy, float w, bool rotate, float gain = 1.0f);
    void slow_down(float v, bool limited);
    void warn_once(uint8_t flags);
    void start_drag(uint8_t flags);
    void drag_step();
    void start_feedback();
    void update_targets();
    void feedback_step(int32_t dt_us);
    int16_t limit(float p);
#if FEATURE_SPEEDCTL
    float integral_rate(uint8_t i, float err, float jump);
#endif
#if FEATURE_VEL_ACCEL
    void accel(float vx, float vy, float w, float k);
#endif
#if FEATURE_TURN_FF
    void turn_feedforward(float vx, float vy, float w);
#endif
#if FEATURE_BRAKE
    void brake_to_rest();
    void slew(int32_t dt_us);
    bool at_rest(int32_t dt_us);
#endif
#if FEATURE_LANDING
    bool lands() const;
    void land_reset();
    void land_start(float ux, float uy, float uw, bool rotate, float goal, float nominal);
    void timed(int64_t duration, int64_t carry);
    void land_step();
    void land_off();
    float land_profile(int32_t dt_us);
    float chain_rest(float need);
    float exit_speed();
#endif
#if FEATURE_PROGRESS
    void watch_start_move(float ux, float uy, float distance_m);
    void watch_step(int32_t dt_us);
#endif
};

extern Executor ex;
// provided by the controller
void on_warn(uint8_t code);
void on_idle();
