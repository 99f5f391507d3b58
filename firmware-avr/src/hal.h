// The board: UART, clock, motor PWM and direction pins, encoders, sonar, battery ADC (docs/uno.md).
#pragma once
#include <stdint.h>

void hal_init();
uint32_t hal_ticks();           // clock timer ticks of 0.5 us, wrapping at 2^32
void hal_wait_for_event();      // idle sleep until a command's end arrives or the 1 ms tick
bool hal_rx_pending();

int16_t uart_read();            // next received byte, -1 when none
void uart_put(char c);          // queues one byte (waits while the transmit ring is full)

void motor_set(uint8_t i, int16_t power);  // signed PWM counts, -255..255; 0 = coast
void motor_brake(uint8_t i);               // L298 fast motor stop (EN high, IN1 = IN2 = 0)
int32_t encoder_count(uint8_t i);

void sonar_trigger();           // 10 us trigger pulse; the echo is timed by input capture
int16_t sonar_result();         // -2 still waiting, else the echo in cm (-1 none yet)
uint16_t battery_mv();
uint16_t battery_adc();  // the raw count, 0..1023 at 0..5 V on the pin
