#include "motion.h"

#include <math.h>
#include <stdlib.h>

#include "cal.h"
#include "hal.h"
#include "safety.h"

#define BRAKED 0x7FFF  // applied[i] of a braked motor: the next power is written whatever it is
#define REACHED 32     // warning flag: a MOVE asked beyond the calibrated reach (power.h, safety.h own 1..16)
#define WATCH_OFF 0    // the progress check's states (progress.py)
#define WATCH_MOVING 1
#define WATCH_COASTING 2

Executor ex;

bool Queue::push(uint8_t kind, const int16_t *p, uint8_t n) {
    if (count >= QUEUE_CAPACITY) return false;
    Slot &s = slots[(head + count) % QUEUE_CAPACITY];
    s.kind = kind;
    for (uint8_t i = 0; i < 5; i++) s.p[i] = i < n ? p[i] : 0;
    count++;
    return true;
}

const Slot &Queue::pop() {
    const Slot &s = slots[head];
    head = (head + 1) % QUEUE_CAPACITY;
    count--;
    return s;
}

void Executor::init() {
    rim_init();
    for (uint8_t i = 0; i < MOTORS; i++) motor_set(i, 0);
    model.scale = 1.0f;
    model.drag_gain = 1.0f;
#if FEATURE_LANDING
    land_scale = 1.0f;
    landing.init();
#endif
}

extern uint8_t batt_level;  // main.cpp: 2 limits the power (battery low)

void Executor::apply() {
    bool sim = (mode & P_MODE_SIMULATION) || coast_us > 0;
    int16_t peak = BATTERY_CAP;  // limited: every wheel scaled alike, keeping the course
    if (batt_level >= 2)
        for (uint8_t i = 0; i < MOTORS; i++)
            if (abs(powers[i]) > peak) peak = abs(powers[i]);
    for (uint8_t i = 0; i < MOTORS; i++) {
        int16_t p = sim ? 0 : powers[i];
        if (peak > BATTERY_CAP) p = (int32_t)p * BATTERY_CAP / peak;
        if (p != applied[i]) {
            applied[i] = p;
            motor_set(i, p);
        }
    }
}

void Executor::set_mode(uint8_t m) {
    uint8_t old = mode;
    mode = m;
#if FEATURE_PROGRESS
    if (m & P_MODE_SIMULATION) watch = WATCH_OFF;  // no power applied: nothing to measure
#endif
#if FEATURE_LANDING
    if (landing.active && !lands()) land_off();
#endif
    if ((old ^ m) & P_MODE_CLOSED_LOOP) {
        if (m & P_MODE_CLOSED_LOOP) {
            start_feedback();
        } else {
            feedback = false;
            if (kind != NONE && kind != K_POWER) start_drag(model.compute(twist[0], twist[1], twist[2], rot, powers));
        }
    }
    apply();
}

bool Executor::stop() {
    bool was = kind != NONE;
    queue.clear();
    kind = NONE;
    watchdog = false;
#if FEATURE_BRAKE
    braking = slewing = false;
#endif
    feedback = dragging = false;
    coast_us = 0;
    speed = 0;
#if FEATURE_PROGRESS
    watch = WATCH_OFF;
#endif
#if FEATURE_LANDING
    landing.rest();
    land_scale = 1.0f;
#endif
    for (uint8_t i = 0; i < MOTORS; i++) powers[i] = 0;
    apply();
    return was;
}

void Executor::brake() {
    for (uint8_t i = 0; i < MOTORS; i++) {
        motor_brake(i);
        applied[i] = BRAKED;
    }
}

void Executor::reset_move() {
    for (uint8_t i = 0; i < 4; i++) remembered[i] = 0;
}

#if FEATURE_VEL_ACCEL
void Executor::vel(int16_t vx, int16_t vy, int16_t w, int16_t t_ms, int16_t a, const int16_t *body) {
    acc_turning = body != 0;
    if (body) {
        acc[0] = body[0] * 0.01f;
        acc[1] = body[1] * 0.01f;
        acc[2] = body[2] * (float)(M_PI / 180);
        acc_on = true;
    } else {
        float v = sqrtf((float)vx * vx + (float)vy * vy);
        acc_on = a != 0 && v > 0;
        float g = acc_on ? a * 0.01f / v : 0.0f;  // 1/s
        acc[0] = g * vx;
        acc[1] = g * vy;
        acc[2] = 0;
    }
#else
void Executor::vel(int16_t vx, int16_t vy, int16_t w, int16_t t_ms) {
#endif
#if FEATURE_PROGRESS
    watch = WATCH_OFF;
#endif
#if FEATURE_BRAKE
    braking = slewing = false;
#endif
#if FEATURE_LANDING
    land_reset();
#endif
    queue.clear();
    if (kind != K_VEL) warned = 0;
    kind = K_VEL;
    infinite = false;
    watchdog = true;
    watchdog_us = (int32_t)t_ms * 1000;
    drive(vx * 0.01f, vy * 0.01f, w * (float)(M_PI / 180), vx == 0 && vy == 0);
}

void Executor::step(int32_t dt_us) {
    if (kind != NONE && !infinite) remaining -= dt_us;
    if (coast_us > 0) {
        coast_us -= dt_us;
        if (coast_us <= 0) apply();
    }
    for (uint8_t guard = 16; guard > 0; guard--) {  // motions started in one step at most
        if (kind == NONE) {
            if (!queue.count) break;
            start_next(0);
        } else if (kind == K_VEL) {
            if (queue.count) {
                watchdog = false;
#if FEATURE_BRAKE
                braking = false;
#endif
                start_next(0);
#if FEATURE_BRAKE
            } else if (braking) {
                if (!slewing && at_rest(dt_us)) finish();
            } else if (watchdog) {
                watchdog_us -= dt_us;
                if (watchdog_us <= 0) {
                    if (feedback) brake_to_rest();
                    else finish();
                }
#else
            } else if (watchdog) {
                watchdog_us -= dt_us;
                if (watchdog_us <= 0) finish();
#endif
            }
            break;
        } else if (infinite) {
            if (!queue.count) break;
            start_next(0);
        } else if (remaining > 0) {
            break;
        } else if (kind == K_DELTA && (reps_inf ? queue.count == 0 : reps > 0)) {
            repeat(remaining);
        } else if (queue.count) {
            start_next(remaining);
        } else {
            finish();
        }
    }
#if FEATURE_PROGRESS
    if (watch == WATCH_COASTING) watch_step(dt_us);
#endif
    if (kind == NONE) return;
#if FEATURE_BRAKE
    if (slewing && kind == K_VEL) {
        slew_due -= dt_us;
        if (slew_due <= 0) slew((int32_t)CONTROL_PERIOD_MS * 1000 - slew_due);
        if (kind == NONE) return;
    }
#endif
    if (feedback) {
        feedback_step(dt_us);
    } else if (dragging) {
        control_due -= dt_us;
        if (control_due <= 0) drag_step();
    }
}

void Executor::finish() {
#if FEATURE_PROGRESS
    bool watched = watch == WATCH_MOVING;
    stop();
    if (watched) {  // the MOVE ended the queue: its coast is watched
        for (uint8_t i = 0; i < MOTORS; i++) watch_last[i] = encoder_count(i);
        watch_coast_us = 0;
        watch_due = (int32_t)CONTROL_PERIOD_MS * 1000;
        watch = WATCH_COASTING;
    }
#else
    stop();
#endif
    on_idle();
}

#if FEATURE_BRAKE
// Brings the robot to rest on the speed loop, then ends the VEL (IDLE) (motion.py brake_to_rest):
// with acceleration limits the twist it drove is slewed down to zero at them; without, the wheels
// are held at rest at once, for at least the body's stopping time from the wheels' speed at the stop
// deceleration. Either way it ends once every wheel stands still (none turned more than its rest
// counts in REST_WINDOW_US), or BRAKE_MAX_US after the twist reached zero.
void Executor::brake_to_rest() {
    braking = true;
    watchdog = false;
    brake_us = 0;
    rest_due = REST_WINDOW_US;
    for (uint8_t i = 0; i < MOTORS; i++) rest_ref[i] = encoder_count(i);
    for (uint8_t i = 0; i < 3; i++) ref[i] = nominal[i];  // the twist asked (the guard scales the driven)
    acc_on = false;
    if (BRAKE_ACCEL_MAX > 0) {
        brake_min_us = 0;
        slewing = true;
        slew((int32_t)CONTROL_PERIOD_MS * 1000);
    } else {
        float fastest = 0;  // the wheels' rim speed now: how long the body may still need to stop
        for (uint8_t i = 0; i < MOTORS; i++) {
            float u = fabsf(wheel_speed[i]) * pgm_read_float(&WHEEL_RADIUS_M[i]);
            if (u > fastest) fastest = u;
        }
        brake_min_us = GUARD_DECEL > 0 ? (int32_t)(fastest / (GUARD_DECEL * 0.01f) * 1e6f) : 0;
        drive(0, 0, 0, false);
    }
}

// Moves the slewed twist towards rest by at most the acceleration limits over dt_us (the translation
// as a vector) and drives it, its rate fed forward as a planned acceleration (motion.py _slew).
void Executor::slew(int32_t dt_us) {
    float dt = dt_us * 1e-6f;
    float dx = -ref[0], dy = -ref[1];
    float dv = sqrtf(dx * dx + dy * dy);
    float most = BRAKE_ACCEL_MAX * dt;
    if (dv > most) {
        dx *= most / dv;
        dy *= most / dv;
    }
    float dw = -ref[2];
    most = BRAKE_ALPHA_MAX > 0 ? BRAKE_ALPHA_MAX * dt : fabsf(dw);
    dw = dw > most ? most : (dw < -most ? -most : dw);
    ref[0] += dx;
    ref[1] += dy;
    ref[2] += dw;
    slewing = ref[0] != 0 || ref[1] != 0 || ref[2] != 0;
    slew_due = (int32_t)CONTROL_PERIOD_MS * 1000;
    // the body's acceleration along its axes: the rate of the body-frame twist less the turning axes'
    acc_on = slewing;
    acc_turning = true;
    acc[0] = slewing ? dx / dt - ref[2] * ref[1] : 0;
    acc[1] = slewing ? dy / dt + ref[2] * ref[0] : 0;
    acc[2] = slewing ? dw / dt : 0;
    if (slewing && SPEED_BAND_INV > 0) rising = (1 << MOTORS) - 1;  // every wheel as after a step
#if FEATURE_SPEEDCTL
    if (slewing) rise_up = rise_down = 0;  // no step to take the sign of: the rise ends within the band
#endif
    drive(ref[0], ref[1], ref[2], ref[0] == 0 && ref[1] == 0);
}

// While braking: true once the wheels stand still (see brake_to_rest).
bool Executor::at_rest(int32_t dt_us) {
    brake_us += dt_us;
    if (brake_us >= BRAKE_MAX_US) return true;
    rest_due -= dt_us;
    if (rest_due > 0) return false;
    rest_due = REST_WINDOW_US;
    bool still = true;
    for (uint8_t i = 0; i < MOTORS; i++) {
        int32_t c = encoder_count(i);
        if (labs(c - rest_ref[i]) > pgm_read_byte(&REST_COUNTS[i])) still = false;
        rest_ref[i] = c;
    }
    return still && brake_us >= brake_min_us;
}
#endif

#if FEATURE_PROGRESS
// Watch a MOVE of `distance_m` along the body-frame unit vector (ux, uy) from the counts now.
void Executor::watch_start_move(float ux, float uy, float distance_m) {
    for (uint8_t i = 0; i < MOTORS; i++) {
        share[i] = pgm_read_float(&TRAVEL[0][i]) * ux + pgm_read_float(&TRAVEL[1][i]) * uy;
        watch_start[i] = encoder_count(i);
    }
    watch_distance = distance_m;
    watch = WATCH_MOVING;
}

// One step of the coast: every control period, once no count moved for one (the wheels stand
// still) or the coast lasted PROGRESS_COAST_MAX_MS, WARN 17 if the travel fell short beyond the
// tolerance (progress.py `step`).
void Executor::watch_step(int32_t dt_us) {
    watch_due -= dt_us;
    if (watch_due > 0) return;
    int32_t elapsed = (int32_t)CONTROL_PERIOD_MS * 1000 - watch_due;  // a slow pass's checks are further apart
    watch_due = (int32_t)CONTROL_PERIOD_MS * 1000;
    watch_coast_us += elapsed;
    bool still = true;
    for (uint8_t i = 0; i < MOTORS; i++) {
        int32_t c = encoder_count(i);
        if (c != watch_last[i]) still = false;
        watch_last[i] = c;
    }
    if (!still && watch_coast_us < PROGRESS_COAST_MAX_MS * 1000L) return;
    watch = WATCH_OFF;
    float s = 0;
    for (uint8_t i = 0; i < MOTORS; i++) s += share[i] * (watch_last[i] - watch_start[i]);
    if (s < (1.0f - PROGRESS_TOLERANCE) * watch_distance) on_warn(P_W_SHORT);
}
#endif

void Executor::start_next(int64_t carry) {
    const Slot &s = queue.pop();
    kind = s.kind;
    warned = 0;
#if FEATURE_PROGRESS
    watch = WATCH_OFF;  // a MOVE starts its own watch (move)
#endif
    if (kind == K_MOVE) {
        for (uint8_t i = 0; i < 4; i++) remembered[i] = s.p[i];
        move(carry);
    } else if (kind == K_DELTA) {
        for (uint8_t i = 0; i < 4; i++) delta[i] = s.p[i];
        reps_inf = s.p[4] == P_INF;
        reps = s.p[4] < 1 ? 1 : s.p[4];
        repeat(carry);
    } else if (kind == K_ROTATE) {
        rotate(s.p[0], s.p[1], carry);
    } else {  // POWER
        infinite = false;
#if FEATURE_LANDING
        land_reset();
#endif
        remaining = (int64_t)s.p[0] * 1000 + carry;
        feedback = dragging = false;
        for (uint8_t i = 0; i < MOTORS; i++) powers[i] = s.p[i + 1];
        apply();
    }
}

static int16_t clamp(int32_t v, int16_t m) { return v > m ? m : (v < -m ? -m : v); }

void Executor::repeat(int64_t carry) {
    if (!reps_inf) reps--;
    int16_t *m = remembered;
    if (abs(m[0]) != P_INF) m[0] = clamp((int32_t)m[0] + delta[0], L_CLAMP);
    int32_t v = (int32_t)m[1] + delta[1];
    if (v != 0 && labs(v) < V_MIN) {
        v = v > 0 ? V_MIN : -V_MIN;
    } else if (labs(v) > V_MAX) {
        v = v > 0 ? V_MAX : -V_MAX;
        warn_once(SATURATED);
    }
    m[1] = v;
    int32_t c = (int32_t)m[2] + delta[2];
    m[2] = c >= 0 ? c % 360 : -((-c) % 360);
    m[3] = clamp((int32_t)m[3] + delta[3], C_CLAMP);
    if (reps_inf && (m[0] == 0 || m[1] == 0)) {  // zero-length: it would spin without moving
        reps_inf = false;
        reps = 0;
    }
    move(carry);
}

// Microseconds for amount / rate, stretched by 1/scale when the powers were saturated.
static int64_t duration(int16_t amount, int16_t rate, float scale) {
    int64_t t = (int64_t)amount * 1000000 / rate;
    if (scale < 1.0f) t = (int64_t)(t / scale);
    return t;
}

void Executor::move(int64_t carry) {
    int16_t L = remembered[0], V = remembered[1], D = remembered[2], C = remembered[3];
    infinite = abs(L) == P_INF;
    if (L == 0 || V == 0) {
#if FEATURE_LANDING
        land_reset();
#endif
        remaining = carry;
        drive(0, 0, 0, false);
        return;
    }
#if FEATURE_REACH
    int16_t v = abs(V);
    if (!(HAS_ENCODERS && (mode & P_MODE_CLOSED_LOOP))) {
        int16_t reach = cal_reach(fold_course(D));
        if (reach > 0 && reach < v) {  // the calibration saw faster MOVEs fall short: the distance first
            v = reach;
            warn_once(REACHED);
        }
    }
#else
#define v abs(V)  // the UNO's image as it was before the reach (an int16_t here costs it 6 B less, not more)
#endif
    float gain = 1.0f;
    if (!infinite) {
        gain += cal_coast(v) * v / abs(L);
        if (gain < 0) gain = 0;
    }
    float s = (L > 0) == (V > 0) ? v : -v;
    float a = D * (float)(M_PI / 180);
#if FEATURE_LANDING
    float u = s > 0 ? 1.0f : -1.0f;
    if (infinite) land_reset();
    else land_start(u * cosf(a), u * sinf(a), u * C * 0.1f, false, abs(L) * 0.01f, v * 0.01f);
    drive(s * 0.01f * cosf(a), s * 0.01f * sinf(a), s * C * 0.001f, false, gain);
    if (!infinite) timed(duration(abs(L), v, time_scale), carry);
#else
    drive(s * 0.01f * cosf(a), s * 0.01f * sinf(a), s * C * 0.001f, false, gain);
    if (!infinite) remaining = duration(abs(L), v, time_scale) + carry;
#endif
#if FEATURE_PROGRESS
    if (!infinite && kind == K_MOVE && !(mode & P_MODE_SIMULATION))  // not when the guard stopped it
        watch_start_move(s > 0 ? cosf(a) : -cosf(a), s > 0 ? sinf(a) : -sinf(a), abs(L) * 0.01f);
#endif
#undef v
}

void Executor::rotate(int16_t A, int16_t F, int64_t carry) {
    infinite = abs(A) == P_INF;
    if (A == 0) {
#if FEATURE_LANDING
        land_reset();
#endif
        remaining = carry;
        drive(0, 0, 0, true);
        return;
    }
    float w = abs(F) * (float)(M_PI / 180);
#if FEATURE_LANDING
    float u = (A > 0) == (F > 0) ? 1.0f : -1.0f;
    if (infinite) land_reset();
    else land_start(0, 0, u, true, abs(A) * (float)(M_PI / 180), w);
    drive(0, 0, u * w, true);
    if (!infinite) timed(duration(abs(A), abs(F), model.scale), carry);
#else
    drive(0, 0, (A > 0) == (F > 0) ? w : -w, true);
    if (!infinite) remaining = duration(abs(A), abs(F), model.scale) + carry;
#endif
}

void Executor::drive(float vx, float vy, float w, bool rotate, float gain) {
    nominal[0] = vx;
    nominal[1] = vy;
    nominal[2] = w;
    nominal[3] = gain;
#if FEATURE_LANDING
    float ls = land_scale;
    if (landing.active) {  // its plan: the share of the twist asked, and its rate of change
        float rate = landing.rate / landing.nominal;  // 1/s
        acc[0] = rate * vx;
        acc[1] = rate * vy;
        acc[2] = rate * w;
        acc_on = rate != 0;
        acc_turning = false;
        vx *= ls;
        vy *= ls;
        w *= ls;
    }
#endif
    float f = 1.0f, v = 0;
    if (vx != 0 || vy != 0) {
        f = guard.factor(vx, vy);
        if (f <= 0) {
            halt = guard.code;
            stop();
            return;
        }
        warn_once(guard.flags);
        if (f < 1.0f) {  // the multiplications only when the guard lowered the speed
            vx *= f;
            vy *= f;
            w *= f;
        }
        v = sqrtf(vx * vx + vy * vy);
        slow_down(v * 100.0f, f < 1.0f);
    } else {
        speed = 0;
        coast_us = 0;
    }
    k = f;
    model.drag_gain = gain;
    // an open-loop VEL: a wheel below the K_l tables' dead band would not turn (WARN 12)
    bool open_vel = kind == K_VEL && (vx != 0 || vy != 0) && !(HAS_ENCODERS && (mode & P_MODE_CLOSED_LOOP));
    model.weak_floor = open_vel ? cal_start_power() : 0;
    uint8_t flags = model.compute(vx, vy, w, rotate, powers, v);
    time_scale = model.scale * f;
    warn_once(flags);
    twist[0] = vx;
    twist[1] = vy;
    twist[2] = w;
    rot = rotate;
#if FEATURE_LANDING
    dead = (flags & DEADBAND) && ls >= 1.0f;  // the loop drives a landing's slow end
#else
    dead = flags & DEADBAND;
#endif
    for (uint8_t i = 0; i < MOTORS; i++) ff[i] = dead ? 0 : model.raw[i];
#if FEATURE_TURN_FF
    if (!dead && w != 0 && !rotate && (mode & P_MODE_CLOSED_LOOP)) turn_feedforward(vx, vy, w);
#endif
#if FEATURE_LANDING
    if (acc_on && (kind == K_VEL || landing.active) && !dead) accel(vx, vy, w, f);
#elif FEATURE_VEL_ACCEL
    if (acc_on && kind == K_VEL && !dead) accel(vx, vy, w, f);
#endif
    if (mode & P_MODE_CLOSED_LOOP) update_targets();  // only the speed loop needs them
    if ((mode & P_MODE_CLOSED_LOOP) && !feedback) {
        start_feedback();
    } else if (feedback) {
        for (uint8_t i = 0; i < MOTORS; i++) powers[i] = limit(ff[i] + correction[i]);
    }
    start_drag(flags);
    apply();
}

// When the guard lowers the speed, coast (powers off) until the robot must have slowed to it:
// reduced power alone decelerates far less than the stop deceleration the guard counts on.
void Executor::slow_down(float v, bool limited) {
    int32_t coast = 0;
    if (limited) {
        float bound = speed + GUARD_DECEL * coast_us * 1e-6f;  // fastest the robot can be going now
        if (bound > v) coast = (int32_t)((bound - v) / GUARD_DECEL * 1e6f);
    }
    speed = v;
    coast_us = coast;
}

void Executor::relimit() {
    if (!travelling()) return;
#if FEATURE_LANDING
    float f = guard.factor(nominal[0] * land_scale, nominal[1] * land_scale);
#else
    float f = guard.factor(nominal[0], nominal[1]);
#endif
    if (f == k) return;
    float old = time_scale;
    drive(nominal[0], nominal[1], nominal[2], rot, nominal[3]);
#if FEATURE_LANDING
    if (kind != NONE && !infinite && kind != K_VEL) {
        if (landing.active) deadline = (int64_t)(deadline * old / time_scale);  // it ends on its distance
        else remaining = (int64_t)(remaining * old / time_scale);
    }
#else
    if (kind != NONE && !infinite && kind != K_VEL) remaining = (int64_t)(remaining * old / time_scale);
#endif
}

void Executor::warn_once(uint8_t flags) {
    uint8_t fresh = flags & ~warned;
    warned |= flags;
    if (fresh & SATURATED) on_warn(P_W_SPEED_REDUCED);
    if (fresh & (DEADBAND | WEAK)) on_warn(P_W_POWER_TOO_LOW);
    if (fresh & LIMITED) on_warn(P_W_SONAR_LIMIT);
    if (fresh & UNCOVERED) on_warn(P_W_UNCOVERED);
#if FEATURE_REACH
    if (fresh & REACHED) on_warn(P_W_REACH);
#endif
}

void Executor::start_drag(uint8_t flags) {
    dragging = !feedback && !(flags & DEADBAND) && model.drags();
    if (dragging) drag_step();
}

void Executor::drag_step() {
    control_due = (int32_t)CONTROL_PERIOD_MS * 1000;
    int32_t counts[MOTORS];
    for (uint8_t i = 0; i < MOTORS; i++) counts[i] = encoder_count(i);
    warn_once(model.drag(counts, powers) & SATURATED);
    apply();
}

// The wheel speeds (rad/s) of the current twist, the speed loop's set points.
void Executor::update_targets() {
    if (dead) {
        for (uint8_t i = 0; i < MOTORS; i++) target[i] = 0;
    } else {
        model.wheel_speeds(twist[0], twist[1], twist[2], target);
#if FEATURE_LANDING
        float over[MOTORS];  // the wheels turn faster by their creep, so the body goes as asked
        if (landing.active && landing.overturn(twist[0], twist[1], twist[2], over))
            for (uint8_t i = 0; i < MOTORS; i++) target[i] += over[i];
#endif
    }
}

void Executor::start_feedback() {
    update_targets();
    for (uint8_t i = 0; i < MOTORS; i++) {
        last_counts[i] = encoder_count(i);
        integ[i] = correction[i] = 0;
        prev_target[i] = 0;  // the wheels taken as at rest: a target that starts them is a step
    }
    rising = 0;
#if FEATURE_SPEEDCTL
    rise_up = rise_down = 0;
    for (uint8_t i = 0; i < MOTORS; i++) held[i] = 0;
#endif
    acc_us = 0;
    feedback = HAS_ENCODERS && (mode & P_MODE_CLOSED_LOOP) && kind != NONE && kind != K_POWER;
}

#if FEATURE_VEL_ACCEL
// The planned acceleration's power added to each wheel's feedforward (the speed loop's), for the
// twist (vx, vy, w) as driven, k the guard's scale of it and of its acceleration (motion.py _accel):
// the body's share of force and torque (ACCEL_BODY_FF) and the wheel's own inertia, through the
// rate of the body-frame twist (ax + w vy, ay - w vx, alpha) with version 4's body acceleration.
#if FEATURE_TURN_FF
// On the closed loop a wheel whose turn is the larger part of its rim speed u is fed at least ROTATE's
// factor at its own speed, K K_r(K |u|) |u| (motion.py Executor._feedforward): K_t, one factor for
// every wheel, leaves the wheels that only turn the body of an arc below what turns them.
void Executor::turn_feedforward(float vx, float vy, float w) {
    float k = cal_k();
    for (uint8_t i = 0; i < MOTORS; i++) {
        float t = rim(i, 0) * vx + rim(i, 1) * vy;
        if (fabsf(rim(i, 2) * w) <= fabsf(t)) continue;
        float u = t + rim(i, 2) * w, least = k * cal_kr(k * fabsf(u)) * fabsf(u);
        if (fabsf(ff[i]) < least && ff[i] * u >= 0) ff[i] = u > 0 ? least : -least;
    }
}
#endif

void Executor::accel(float vx, float vy, float w, float k) {
    float a[3] = {acc[0] * k, acc[1] * k, acc[2] * k};
    float r[3] = {a[0], a[1], a[2]};
    if (acc_turning) {
        r[0] += w * vy;
        r[1] -= w * vx;
    }
    for (uint8_t i = 0; i < MOTORS; i++)
        for (uint8_t j = 0; j < 3; j++)
            ff[i] += pgm_read_float(&ACCEL_BODY_FF[i][j]) * a[j] + pgm_read_float(&ACCEL_WHEEL_FF[i][j]) * r[j];
}
#endif

int16_t Executor::limit(float p) {
    if (p >= PWM_MAX) return PWM_MAX;
    if (p <= -PWM_MAX) return -PWM_MAX;
    return lroundf(p);
}

#if FEATURE_SPEEDCTL
// Wheel i's integral rate this period, its target having moved by `jump` rad/s and its error `err`
// (speedctl.py update): a jump beyond the band starts a rise that lasts until the wheel reaches the
// target (its error changes sign; after a slew, with no step to take the sign of, until it is within
// the band), its rate 1 / (1 + (err / band)^2); a target held STEADY_PERIODS periods, not 0, past
// its rise, integrates at SPEED_STEADY (ki_steady / ki); any other at the full rate.
float Executor::integral_rate(uint8_t i, float err, float jump) {
    uint8_t bit = 1 << i;
    float x = jump * SPEED_BAND_INV, e = err * SPEED_BAND_INV;
    if (x > 1 || x < -1) {
        rising |= bit;
        rise_up = err > 0 ? rise_up | bit : rise_up & ~bit;
        rise_down = err > 0 ? rise_down & ~bit : rise_down | bit;
    } else if ((rise_up | rise_down) & bit) {
        if (rise_up & bit ? err <= 0 : err >= 0) {  // reached
            rising &= ~bit;
            rise_up &= ~bit;
            rise_down &= ~bit;
        }
    } else if (e <= 1 && e >= -1) {
        rising &= ~bit;
    }
    if (jump != 0 || target[i] == 0 || (rising & bit)) held[i] = 0;
    else if (held[i] < STEADY_PERIODS) held[i]++;
    if (rising & bit) return 1 / (1 + e * e);
    return held[i] >= STEADY_PERIODS ? SPEED_STEADY : 1.0f;
}
#endif

// PI on each wheel's encoder-measured speed every control period, integral frozen while saturated;
// after a step in a wheel's target it grows slower the larger the error, until the wheel is within
// the band (FEATURE_SPEEDCTL: integral_rate); the integral learns the error against the target the
// period was driven for, the P term the new one (speedctl.py).
void Executor::feedback_step(int32_t dt_us) {
#if FEATURE_LANDING
    if (landing.active) {
        land_us += dt_us;
        deadline -= dt_us;
    }
#endif
    acc_us += dt_us;
    if (acc_us < (int32_t)CONTROL_PERIOD_MS * 1000) return;
    float dt = acc_us * 1e-6f;
    acc_us = 0;
    for (uint8_t i = 0; i < MOTORS; i++) {
        int32_t c = encoder_count(i);
        float speed = (c - last_counts[i]) * (6.2831853f / pgm_read_word(&ENCODER_CPR[i])) / dt;
        last_counts[i] = c;
#if FEATURE_BRAKE
        wheel_speed[i] = speed;
#endif
        float err = target[i] - speed;
        correction[i] = SPEED_KP * err + SPEED_KI * integ[i];
        float p = ff[i] + correction[i];
        float late = prev_target[i] - speed;  // against the target the period was driven for
#if FEATURE_SPEEDCTL
        float rate = integral_rate(i, err, target[i] - prev_target[i]);
        prev_target[i] = target[i];
        if (-PWM_MAX < p && p < PWM_MAX) integ[i] += late * dt * rate;
#else
        float x = (target[i] - prev_target[i]) * SPEED_BAND_INV;
        prev_target[i] = target[i];
        if (x > 1 || x < -1) {
            rising |= 1 << i;
        } else if (err * SPEED_BAND_INV <= 1 && err * SPEED_BAND_INV >= -1) {
            rising &= ~(1 << i);
        }
        if (-PWM_MAX < p && p < PWM_MAX) {
            x = rising & (1 << i) ? err * SPEED_BAND_INV : 0;
            integ[i] += late * dt / (1 + x * x);
        }
#endif
        powers[i] = limit(p);
    }
#if FEATURE_LANDING
    if (landing.active) land_step();
#endif
    apply();
}

#if FEATURE_LANDING
// A finite motion started now ends on its encoders: closed loop, not simulating (motion.py _lands).
bool Executor::lands() const { return HAS_ENCODERS && (mode & P_MODE_CLOSED_LOOP) && !(mode & P_MODE_SIMULATION); }

// The motion starting is not landed: full speed, on the timeline.
void Executor::land_reset() {
    landing.active = false;
    land_scale = 1.0f;
}

// Lands the motion starting now (if it lands): twist (ux, uy, uw) per unit of its speed, `goal` m
// (rad) asked at `nominal` m/s (rad/s); its plan set before it is driven.
void Executor::land_start(float ux, float uy, float uw, bool rotate, float goal, float nominal_speed) {
    if (!lands()) return land_reset();
    int32_t counts[MOTORS];
    for (uint8_t i = 0; i < MOTORS; i++) counts[i] = encoder_count(i);
    unit[0] = ux;
    unit[1] = uy;
    unit[2] = uw;
    landing.start(counts, unit, rotate, goal, nominal_speed, feedback ? wheel_speed : 0, land_us);
    land_us = 0;
    land_scale = land_profile(0);
}

// A finite motion's time: on the timeline, or (landing) a deadline of twice it with its ramps and a
// second, after which it ends short, its end left to land_step.
void Executor::timed(int64_t d, int64_t carry) {
    if (landing.active) {
        float a = landing.rotate ? LAND_ACCEL_W : LAND_ACCEL;
        deadline = 2 * (d + (int64_t)(2e6f * landing.nominal / a)) + 1000000;
        remaining = landing.time_left((int32_t)CONTROL_PERIOD_MS * 1000);
    } else {
        remaining = d + carry;
    }
}

// One control period of a landing motion: its travel, its end, its ramp (last_counts: the loop's).
void Executor::land_step() {
    int32_t dt = land_us;
    landing.update(last_counts, dt);
    land_us = 0;
    remaining = deadline <= 0 ? 0 : landing.time_left((int32_t)CONTROL_PERIOD_MS * 1000);
    float rate = landing.rate;
    float scale = land_profile(dt);
    if (scale != land_scale || landing.rate != rate) {
        land_scale = scale;
        drive(nominal[0], nominal[1], nominal[2], rot, nominal[3]);
    }
}

// Back to the timeline mid-motion (open loop or simulation now): the rest at the speed asked.
void Executor::land_off() {
    float left = landing.left();
    land_reset();
    remaining = left > 0 ? (int64_t)(left / landing.nominal * 1e6f) : 0;
    if (kind != NONE) drive(nominal[0], nominal[1], nominal[2], rot, nominal[3]);
}

// Advances the landing motion's plan by dt_us: the share of the asked speed to drive now.
float Executor::land_profile(int32_t dt_us) {
    float need = landing.braking();
    float rest = kind == K_DELTA ? chain_rest(need) : 0;
    float v_exit = rest >= need ? 0 : exit_speed();
    return landing.replan(rest, v_exit, dt_us);
}

// The path (m) of this DELTA's repetitions still to come, counted up to `need`.
float Executor::chain_rest(float need) {
    if (reps_inf) return queue.count == 0 ? need : 0;
    int16_t L = remembered[0];
    float total = 0;
    uint16_t k = reps;
    for (uint8_t guard_n = LAND_CHAIN_GUARD; k > 0 && total < need; k--) {
        if (--guard_n == 0) return need;
        L = clamp((int32_t)L + delta[0], L_CLAMP);
        total += abs(L) * 0.01f;
    }
    return total;
}

// The speed the command queued behind keeps along this motion's direction (m/s or rad/s; 0 when it
// goes elsewhere, turns the other way or nothing is queued).
float Executor::exit_speed() {
    if (!queue.count) return 0;
    const Slot &s = queue.slots[queue.head];
    float v;
    if (landing.rotate) {
        if (s.kind != K_ROTATE || s.p[0] == 0) return 0;
        float sign = (s.p[0] > 0) == (s.p[1] > 0) ? 1.0f : -1.0f;
        v = sign * landing.uw * abs(s.p[1]) * (float)(M_PI / 180);
    } else if (s.kind == K_MOVE || s.kind == K_DELTA) {
        int32_t L = s.p[0], V = s.p[1], D = s.p[2];
        if (s.kind == K_DELTA) {
            L += remembered[0];
            V += remembered[1];
            D += remembered[2];
        }
        if (L == 0 || V == 0) return 0;
        float sp = labs(V) * 0.01f;
        if ((L > 0) != (V > 0)) sp = -sp;
        float a = D * (float)(M_PI / 180);
        v = sp * (cosf(a) * landing.ux + sinf(a) * landing.uy);
    } else {
        return 0;
    }
    return v > 0 ? v : 0;
}
#endif
