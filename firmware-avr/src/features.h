// Compile-time switches of what the Arduino Mega 2560 runs beyond the UNO, whose flash cannot hold it
// (docs/uno.md, "The Arduino Mega 2560"). The Mega's generated header sets each FEATURE_* to 1 with
// its constants (avrgen_features.h.in); the UNO's sets none, and every one is 0 here, so the UNO's
// image is the one it was without them.
#pragma once

#ifndef FEATURE_VEL_ACCEL  // protocol versions 3 and 4: VEL's planned acceleration (motion.py _accel)
#define FEATURE_VEL_ACCEL 0
#define P_VERSION_MAX P_PROTOCOL_VERSION
#define P_VEL_PARAMS_MAX P_PARAMS_MAX
#endif
#ifndef FEATURE_PROGRESS  // the MOVE progress check on the encoders, WARN 17 (progress.py)
#define FEATURE_PROGRESS 0
#endif
#ifndef FEATURE_REACH  // the calibrated reach, CAL table 8 and WARN 18 (motion.py _move)
#define FEATURE_REACH 0
#endif
#ifndef FEATURE_BRAKE  // a VEL's watchdog on the closed loop brakes to rest (motion.py brake_to_rest)
#define FEATURE_BRAKE 0
#endif
#ifndef FEATURE_LANDING  // MODE 2's finite motions end on the encoders, CAL table 9 (landing.py)
#define FEATURE_LANDING 0
#endif
#ifndef FEATURE_SPEEDCTL  // the speed loop as speedctl.py: a step's rise until the target, a held target's faster integral
#define FEATURE_SPEEDCTL 0
#endif
#ifndef FEATURE_TURN_FF  // on the closed loop a wheel that mostly turns the body fed ROTATE's K_r (motion.py _feedforward)
#define FEATURE_TURN_FF 0
#endif
#if FEATURE_LANDING && !FEATURE_BRAKE
#error "the landing starts its plan from the speed loop's wheel speeds (FEATURE_BRAKE keeps them)"
#endif
#if FEATURE_BRAKE && !FEATURE_VEL_ACCEL
#error "braking to rest feeds its slew forward as a planned acceleration: it needs FEATURE_VEL_ACCEL"
#endif
// the most parameters one command may carry: VEL's 7 with version 4, else P_PARAMS_MAX
#define CMD_PARAMS_MAX (P_VEL_PARAMS_MAX > P_PARAMS_MAX ? P_VEL_PARAMS_MAX : P_PARAMS_MAX)
