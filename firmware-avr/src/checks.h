// Parameter checks of every command (firmware/limits.py): 0 or the ERROR code.
#pragma once
#include <stdint.h>

#include "features.h"

#define UNO_MODE_MASK                                                                                \
    (P_MODE_SIMULATION | P_MODE_CLOSED_LOOP | P_MODE_BINARY | P_MODE_REFUSE_UNCOVERED | P_MODE_CHECKED_TEXT | \
     P_MODE_SEQUENCED_TEXT)

// `n` parameters in `p`; `lo`..`hi` is the command's own parameter count.
uint8_t check(uint8_t kw, const int16_t *p, uint8_t n, uint8_t lo, uint8_t hi);
