// The board's microcontroller: the registers and vectors hal.cpp names for its clock timer and UART.
// The Arduino UNO (ATmega328P) keeps timer 1 as the clock, its input capture ICP1 on D8 timing the
// sonar's echo; the Arduino Mega 2560 (ATmega2560) does not break ICP1 (PD4) out to a header, so
// there the clock is timer 5, whose ICP5 is D48. Everything else (pins, timers 0 and 2 for the
// motors' PWM, the pin-change groups of the encoders) comes from the generated header (docs/uno.md).
// The Mega's 8 KB of SRAM also buy a 1 KB receive ring (the UNO's: 256 B) and the protocol's full
// binary window of P_WINDOW frames, as the MicroPython firmware takes (the UNO's: P_WINDOW_MIN);
// kept replies of up to 32 frame bytes, so a duplicate STATUS gets its kept reply as on the
// MicroPython firmware (the UNO keeps 16: OK, ERROR, HELLO, and runs a STATUS again), 16 events
// waiting for the send window (binlink.py's; the UNO's: 8), and frames of any length received (a
// command with too many integers is ERROR 24; the UNO drops chunks over 48 bytes unanswered).
#pragma once
#include <avr/io.h>

#if defined(__AVR_ATmega2560__)
#define BOARD_RX_SIZE 1024  // 32 command frames of at most 25 bytes
#define BOARD_WINDOW P_WINDOW
#define BOARD_KEPT_BYTES 32  // a STATUS reply: at most 26 bytes (4 powers of 2, 4 MOVE fields of 3)
#define BOARD_BACKLOG 16
#define BOARD_CHUNK_MAX 255  // any frame (its length byte says at most 255): too many integers is ERROR 24
#define CLK_TCCRA TCCR5A
#define CLK_TCCRB TCCR5B
#define CLK_TCNT TCNT5
#define CLK_OCRB OCR5B
#define CLK_ICR ICR5
#define CLK_TIMSK TIMSK5
#define CLK_TIFR TIFR5
#define CLK_CS1 CS51
#define CLK_ICNC ICNC5
#define CLK_ICES ICES5
#define CLK_TOIE TOIE5
#define CLK_OCIEB OCIE5B
#define CLK_ICIE ICIE5
#define CLK_TOV TOV5
#define CLK_ICF ICF5
#define CLK_OVF_vect TIMER5_OVF_vect
#define CLK_COMPB_vect TIMER5_COMPB_vect
#define CLK_CAPT_vect TIMER5_CAPT_vect
#define UART_RX_vect USART0_RX_vect
#define UART_UDRE_vect USART0_UDRE_vect
#elif defined(__AVR_ATmega328P__)
#define BOARD_RX_SIZE 256
#define BOARD_WINDOW P_WINDOW_MIN
#define BOARD_KEPT_BYTES 16
#define BOARD_BACKLOG 8
#define BOARD_CHUNK_MAX 48  // command frames are at most 34 bytes (5 varints of 5, VEL's 7 of 3)
#define CLK_TCCRA TCCR1A
#define CLK_TCCRB TCCR1B
#define CLK_TCNT TCNT1
#define CLK_OCRB OCR1B
#define CLK_ICR ICR1
#define CLK_TIMSK TIMSK1
#define CLK_TIFR TIFR1
#define CLK_CS1 CS11
#define CLK_ICNC ICNC1
#define CLK_ICES ICES1
#define CLK_TOIE TOIE1
#define CLK_OCIEB OCIE1B
#define CLK_ICIE ICIE1
#define CLK_TOV TOV1
#define CLK_ICF ICF1
#define CLK_OVF_vect TIMER1_OVF_vect
#define CLK_COMPB_vect TIMER1_COMPB_vect
#define CLK_CAPT_vect TIMER1_CAPT_vect
#define UART_RX_vect USART_RX_vect
#define UART_UDRE_vect USART_UDRE_vect
#else
#error "omnibot's AVR firmware is built for the ATmega328P (UNO) or the ATmega2560 (Mega): make BOARD=uno|mega"
#endif
