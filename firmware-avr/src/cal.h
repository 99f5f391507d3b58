// Seed 000's calibration tables (K, K_t, K_r, K_l curves) and the motor map, kept in EEPROM so a
// calibration survives a power cycle; CAL writes one knot (docs/protocol.md, CAL).
#pragma once
#include <stdint.h>

#include "features.h"

void cal_init();              // loads the generated defaults when the EEPROM holds none for this robot
bool cal_write(int16_t table, int16_t index, int16_t x, int16_t y);  // CAL,T,I,X,Y; false: ERROR 38
float cal_k();                // PWM counts per m/s of rim speed
float cal_kt(float power);
float cal_kr(float power);
float cal_kl(float power, float folded_course);
int16_t cal_start_power();  // the K_l tables' dead band, whole PWM counts up (0: they do not say)
float cal_coast(float speed_cms);  // s
float cal_motor_power(uint8_t i, float a, float u);  // nominal power a, rim speed u (m/s)
float cal_roller(uint8_t which, uint8_t i);  // which 0: cosine, 1: sine coefficient, PWM counts
bool cal_any_roller_drag();  // some roller drag coefficient is not 0
#if FEATURE_REACH
int16_t cal_reach(float folded_course);  // the calibrated reach, cm/s (0: none known)
#endif
