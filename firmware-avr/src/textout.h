// Text output helpers for reply and event lines.
#pragma once
#include <avr/pgmspace.h>
#include <stdint.h>

void out_P(PGM_P s);
void out_s(const char *s);
void out_i(int32_t v);
void out_u(uint32_t v);
void comma_i(int32_t v);  // ",<v>"
void end_line();          // CR LF
