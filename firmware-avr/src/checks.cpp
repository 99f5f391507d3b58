// Parameter checks of every command against the protocol and the robot's limits (firmware/limits.py).
#include "checks.h"

// |v| as an unsigned 16-bit value: abs(-32768) overflows int16 and stays negative, which passed
// every "abs(x) > limit" check (a VEL of -32768 drove every motor at -255); 32768 here fails them.
static uint16_t mag(int16_t v) { return v < 0 ? (uint16_t)(0u - (uint16_t)v) : (uint16_t)v; }

// vx^2 + vy^2 unsigned: two -32768s make 2^31, one past int32's range (their int32 sum wrapped
// negative and passed V_MAX_SQ: VEL,-32768,-32768,0,1000 drove every motor at full power).
static uint32_t speed_sq(int16_t vx, int16_t vy) {
    uint32_t x = mag(vx), y = mag(vy);
    return x * x + y * y;
}

static uint8_t check_move(int16_t L, int16_t V, int16_t D, int16_t C, uint8_t k) {
    if (mag(L) >= (k == 1 ? L_MAX_EXCL : L2_MAX_EXCL) && !(k == 1 && mag(L) == P_INF)) return P_E_DISTANCE;
    if (k == 1) {
        if (mag(V) < V_MIN || mag(V) > V_MAX || V == 0) return P_E_SPEED;
    } else if (mag(V) > V2_MAX) {
        return P_E_SPEED;
    }
    if (mag(D) >= 360 * k) return P_E_COURSE;
    if (mag(C) >= (k == 1 ? C_MAX_EXCL : C2_MAX_EXCL)) return P_E_CURVATURE;
    return 0;
}

uint8_t check(uint8_t kw, const int16_t *p, uint8_t n, uint8_t lo, uint8_t hi) {
#if FEATURE_VEL_ACCEL
    if (kw == K_VEL) hi = n == 6 ? 4 : P_VEL_PARAMS_MAX;  // 4, 5 (A) or 7 (AX, AY, AW)
#endif
    if (n < lo || n > hi) return P_E_PARAM_COUNT;
    switch (kw) {
        case K_MOVE:
            return check_move(p[0], p[1], p[2], p[3], 1);
        case K_DELTA:
            if (p[4] < 0 || p[4] > P_INF) return P_E_REPEAT;
            return check_move(p[0], p[1], p[2], p[3], 2);
        case K_ROTATE:
            if (mag(p[0]) > P_INF) return P_E_ANGLE;
            if (p[1] == 0 || mag(p[1]) >= F_MAX_EXCL) return P_E_SPEED;
            return 0;
        case K_POWER:
            if (p[0] < 1 || p[0] > 30000) return P_E_TIME;
            for (uint8_t i = 1; i < n; i++)
                if (mag(p[i]) > PWM_MAX) return P_E_SPEED;
            return 0;
        case K_VEL:
            if (speed_sq(p[0], p[1]) > V_MAX_SQ || mag(p[2]) >= F_MAX_EXCL) return P_E_SPEED;
            if (p[3] < 1 || p[3] > 1000) return P_E_TIME;
            return 0;
        case K_SONAR:
            if (p[0] < 1 || p[0] > SONARS) return P_E_SONAR;
            if (p[1] != 0 && (p[1] < SONAR_PERIOD_MIN || p[1] > 30000)) return P_E_SONAR_PERIOD;
            for (uint8_t i = 2; i < 5; i++)
                if (p[i] < 0 || p[i] > 500) return P_E_SONAR;
            return 0;
        case K_TELEM:
            if (p[0] != 0 && (p[0] < P_TEL_PERIOD_MIN || p[0] > 30000)) return P_E_TIME;
            if (p[1] & ~P_TEL_MASK) return P_E_UNSUPPORTED;
            return 0;
        case K_MODE:
            if (p[0] & ~UNO_MODE_MASK) return P_E_UNSUPPORTED;
            if ((p[0] & P_MODE_CLOSED_LOOP) && !HAS_ENCODERS) return P_E_UNSUPPORTED;
            return 0;
        case K_HELLO:
            for (uint8_t i = 0; i < n; i++)
#if FEATURE_VEL_ACCEL
                if (p[i] >= P_PROTOCOL_VERSION && p[i] <= P_VERSION_MAX) return 0;
#else
                if (p[i] == P_PROTOCOL_VERSION) return 0;
#endif
            return n ? P_E_UNSUPPORTED : 0;
    }
    return 0;
}

