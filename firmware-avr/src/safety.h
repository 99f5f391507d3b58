// The sonar stop's guard (firmware/safety.py, docs/safety.md) for the UNO's one sonar: the speed the
// robot may travel at given what the sonar sees, and whether a direction is covered.
#pragma once
#include <stdint.h>

#define LIMITED 4  // executor warning flags (power.h owns 1 and 2)
#define UNCOVERED 8

struct SonarGuard {
    uint16_t period;  // the sonar's SONAR P and STOP (main.cpp writes them)
    int16_t stop;
    float range, room;  // last range and the travel room it leaves, cm (-1: none)
    float closing;      // closing speed of the last factor, cm/s
    bool missed, refuse;
    uint8_t code, flags;

    bool armed() const { return period > 0 && stop > 0; }
    void reading(int16_t cm);  // a new reading (-1: no echo)
    void clear();              // the sonar was reconfigured
    bool below_stop() const;   // for motions without travel
    bool covers(float vx, float vy) const;
    float factor(float vx, float vy);  // scale (0..1] for travel at (vx, vy) m/s; 0: stop (code)
};

extern SonarGuard guard;
