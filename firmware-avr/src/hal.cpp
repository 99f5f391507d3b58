// The board's peripherals (board.h names them: ATmega328P or ATmega2560). The clock timer (timer 1
// on the UNO, 5 on the Mega; prescaler 8, 0.5 us) times the sonar echo by input capture (ICP1 on D8,
// ICP5 on D48); its compare B wakes the main loop every millisecond. Timers 0 and 2 give the motors'
// PWM (fast PWM, prescaler 64: 976 Hz). USART0 runs at 115200 baud (U2X).
#include "hal.h"
#include "board.h"

#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/sleep.h>
#include <util/atomic.h>
#include <util/delay.h>

#define RX_SIZE BOARD_RX_SIZE  // powers of two; 256 (the UNO's): an 8-bit index wraps by itself
#define TX_SIZE 128

static volatile uint8_t rx_buf[RX_SIZE];
#if RX_SIZE > 256  // 16-bit indices: the main loop reads and writes them with interrupts off
typedef uint16_t RxIndex;
#define RX_ATOMIC ATOMIC_BLOCK(ATOMIC_RESTORESTATE)
#else
typedef uint8_t RxIndex;
#define RX_ATOMIC
#endif
static volatile RxIndex rx_head, rx_tail;
static volatile uint8_t tx_buf[TX_SIZE];
static volatile uint8_t tx_head, tx_tail;
static volatile uint16_t overflows;
// Single-channel encoders: an edge says that a wheel turned, not which way. It is counted in the
// direction the wheel last took (`turn`), which follows the sign of the motor's power (`drive`) only
// once the wheel can have turned around: a power against a turning wheel brakes it first (a
// reversal; the closed loop braking a wheel, or dithering the sign of an idle one around zero
// speed), and the edges of that while are the old direction's. At an edge after a power of the
// other sign the wheel has turned around if it had made no edge for ENC_STOP_MS (it had stopped),
// or under a strong power (at least ENC_STRONG, well above the motors' dead band: it turns the
// wheel around quickly) for ENC_TURN_MS (the pause at the turnaround). At the latest it follows
// once the power has had its sign for ENC_HOLD_MS (strong) or 255 ms (weak): a wheel can turn
// around without a pause (one at rest on an edge's brink, one that slips), and the closed loop,
// measuring a speed against its power, would push it faster still (docs/uno.md).
#define ENC_STOP_MS 30  // 1 edge in 30 ms: 0.5 rad/s with 440 edges a turn, 1.2 cm/s on a 2.5 cm wheel
#define ENC_TURN_MS 5   // the simulated omni4 pauses 10-15 ms at a turnaround under a strong power
#define ENC_HOLD_MS 20  // a strong power stops the simulated omni4's wheels from full speed in 20 ms
#define ENC_STRONG 64   // PWM counts (omni4's dead band is about 44)

struct Wheel {
    int8_t turn;    // the direction counted: -1, 0 (never driven), 1
    int8_t drive;   // the last non-zero power's sign, doubled when strong
    uint8_t quiet;  // ms since the last edge, up to 255
    uint8_t age;    // ms since the power took its sign, up to 255
};

static volatile int32_t enc[MOTORS];
static Wheel wheel[MOTORS];
static uint8_t enc_level;  // bit i: motor i's encoder pin as last seen
static volatile uint16_t echo_start;
static volatile uint8_t echo_state;  // 0 idle, 1 waiting for the rising edge, 2 for the falling one, 3 done
static volatile uint16_t echo_ticks;

// Set when the main loop has work: a command's end arrived, or the 1 ms tick. The bytes before a
// command's end wait in the ring: a pass woken by each of them cost more than the command itself.
static volatile bool wake;

ISR(UART_RX_vect) {
    uint8_t c = UDR0;
    RxIndex next = (rx_head + 1) & (RX_SIZE - 1);
    if (next != rx_tail) {
        rx_buf[rx_head] = c;
        rx_head = next;
    }
    if (c == '\n' || c == '\r' || c == ';') wake = true;
}

ISR(UART_UDRE_vect) {
    if (tx_head == tx_tail) {
        UCSR0B &= ~_BV(UDRIE0);
        return;
    }
    UDR0 = tx_buf[tx_tail];
    tx_tail = (tx_tail + 1) & (TX_SIZE - 1);
}

ISR(CLK_OVF_vect) { overflows++; }

ISR(CLK_COMPB_vect) {  // 1 ms: wakes the main loop, times the encoders' pauses
    CLK_OCRB += 2000;
    wake = true;
    for (Wheel &w : wheel) {
        if (w.quiet != 255) w.quiet++;
        if (w.age != 255) w.age++;
    }
}

ISR(CLK_CAPT_vect) {
    uint16_t t = CLK_ICR;
    if (echo_state == 1) {
        echo_start = t;
        CLK_TCCRB &= ~_BV(CLK_ICES);  // now the falling edge
        echo_state = 2;
    } else if (echo_state == 2) {
        echo_ticks = t - echo_start;
        echo_state = 3;
        CLK_TIMSK &= ~_BV(CLK_ICIE);
    }
}

static inline void count_edge(Wheel &w, volatile int32_t &count) {
    int8_t s = w.drive;
    bool strong = s == 2 || s == -2;
    if (strong) s /= 2;
    if (s != w.turn && (w.quiet >= (strong ? ENC_TURN_MS : ENC_STOP_MS) || w.age >= (strong ? ENC_HOLD_MS : 255)))
        w.turn = s;
    w.quiet = 0;
    count += w.turn;
}

// Every pin-change group runs this one handler: it finds which encoder pins changed.
ISR(PCINT0_vect) {
    uint8_t now = 0;
#define ENC_LEVEL(i) \
    if (M##i##_ENC_PIN & _BV(M##i##_ENC_BIT)) now |= _BV(i);
    ENC_LEVEL(0)
#if MOTORS > 1
    ENC_LEVEL(1)
#endif
#if MOTORS > 2
    ENC_LEVEL(2)
#endif
#if MOTORS > 3
    ENC_LEVEL(3)
#endif
    uint8_t changed = now ^ enc_level;
    enc_level = now;
    for (uint8_t i = 0; i < MOTORS; i++, changed >>= 1)
        if (changed & 1) count_edge(wheel[i], enc[i]);
}
ISR(PCINT1_vect, ISR_ALIASOF(PCINT0_vect));
ISR(PCINT2_vect, ISR_ALIASOF(PCINT0_vect));

#define PIN_OUT(p) (p##_DDR |= _BV(p##_BIT))
#define PIN_SET(p, v) ((v) ? (p##_PORT |= _BV(p##_BIT)) : (p##_PORT &= ~_BV(p##_BIT)))

void hal_init() {
    // UART 115200 8N1, double speed
    UCSR0A = _BV(U2X0);
    UBRR0 = (F_CPU / 8 / BAUD) - 1;
    UCSR0B = _BV(RXEN0) | _BV(TXEN0) | _BV(RXCIE0);
    UCSR0C = _BV(UCSZ01) | _BV(UCSZ00);
    // the clock timer: normal mode, prescaler 8, overflow + compare B + (on demand) capture interrupts
    CLK_TCCRA = 0;
    CLK_TCCRB = _BV(CLK_CS1) | _BV(CLK_ICNC);
    CLK_OCRB = 2000;
    CLK_TIMSK = _BV(CLK_TOIE) | _BV(CLK_OCIEB);
    // timers 0 and 2: fast PWM, prescaler 64; outputs connected per motor when it runs
    TCCR0A = _BV(WGM01) | _BV(WGM00);
    TCCR0B = _BV(CS01) | _BV(CS00);
    TCCR2A = _BV(WGM21) | _BV(WGM20);
    TCCR2B = _BV(CS22);
#define MOTOR_PINS(i)        \
    PIN_OUT(M##i##_PWM);     \
    PIN_OUT(M##i##_IN1);     \
    PIN_OUT(M##i##_IN2);     \
    PCICR |= _BV(M##i##_ENC_PCIE); \
    M##i##_ENC_PCMSK |= _BV(M##i##_ENC_PCINT & 7);
    MOTOR_PINS(0)
#if MOTORS > 1
    MOTOR_PINS(1)
#endif
#if MOTORS > 2
    MOTOR_PINS(2)
#endif
#if MOTORS > 3
    MOTOR_PINS(3)
#endif
#define ENC_INIT(i) \
    if (M##i##_ENC_PIN & _BV(M##i##_ENC_BIT)) enc_level |= _BV(i);
    ENC_INIT(0)
#if MOTORS > 1
    ENC_INIT(1)
#endif
#if MOTORS > 2
    ENC_INIT(2)
#endif
#if MOTORS > 3
    ENC_INIT(3)
#endif
#if SONARS
    SONAR_TRIG_DDR |= _BV(SONAR_TRIG_BIT);
#endif
    // ADC: AVcc reference, prescaler 128
    ADMUX = _BV(REFS0) | BATTERY_ADC;
    ADCSRA = _BV(ADEN) | _BV(ADPS2) | _BV(ADPS1) | _BV(ADPS0);
    set_sleep_mode(SLEEP_MODE_IDLE);
    sei();
}

uint32_t hal_ticks() {
    uint16_t hi, lo;
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE) {
        hi = overflows;
        lo = CLK_TCNT;
        if ((CLK_TIFR & _BV(CLK_TOV)) && lo < 0x8000) hi++;
    }
    return ((uint32_t)hi << 16) | lo;
}

bool hal_rx_pending() {
    bool pending;
    RX_ATOMIC { pending = rx_head != rx_tail; }
    return pending;
}

void hal_wait_for_event() {
    cli();
    while (!wake) {  // other interrupts (a byte inside a command, encoder edges, the UART's sending) sleep on
        sleep_enable();
        sei();
        sleep_cpu();
        sleep_disable();
        cli();
    }
    wake = false;
    sei();
}

int16_t uart_read() {
    RxIndex head;
    RX_ATOMIC { head = rx_head; }
    if (head == rx_tail) return -1;
    uint8_t c = rx_buf[rx_tail];
    RX_ATOMIC { rx_tail = (rx_tail + 1) & (RX_SIZE - 1); }
    return c;
}

void uart_put(char c) {
    uint8_t next = (tx_head + 1) & (TX_SIZE - 1);
    while (next == tx_tail) {
    }
    tx_buf[tx_head] = c;
    tx_head = next;
    UCSR0B |= _BV(UDRIE0);
}

void motor_set(uint8_t i, int16_t p) {
    uint8_t duty = p < 0 ? -p : p;
    if (p != 0) {  // the encoder's direction follows (count_edge)
        int8_t s = duty >= ENC_STRONG ? (p > 0 ? 2 : -2) : (p > 0 ? 1 : -1);
        if ((s ^ wheel[i].drive) < 0) wheel[i].age = 0;
        wheel[i].drive = s;
    }
#define MOTOR_SET(k)                                    \
    case k:                                             \
        M##k##_OCR = duty;                              \
        if (duty) M##k##_TCCR |= _BV(M##k##_COM);       \
        else M##k##_TCCR &= ~_BV(M##k##_COM);           \
        PIN_SET(M##k##_PWM, 0);                         \
        PIN_SET(M##k##_IN1, p > 0);                     \
        PIN_SET(M##k##_IN2, p < 0);                     \
        break;
    switch (i) {
        MOTOR_SET(0)
#if MOTORS > 1
        MOTOR_SET(1)
#endif
#if MOTORS > 2
        MOTOR_SET(2)
#endif
#if MOTORS > 3
        MOTOR_SET(3)
#endif
    }
}

void motor_brake(uint8_t i) {
#define MOTOR_BRAKE(k)                         \
    case k:                                    \
        M##k##_TCCR &= ~_BV(M##k##_COM);       \
        PIN_SET(M##k##_IN1, 0);                \
        PIN_SET(M##k##_IN2, 0);                \
        PIN_SET(M##k##_PWM, 1);                \
        break;
    switch (i) {
        MOTOR_BRAKE(0)
#if MOTORS > 1
        MOTOR_BRAKE(1)
#endif
#if MOTORS > 2
        MOTOR_BRAKE(2)
#endif
#if MOTORS > 3
        MOTOR_BRAKE(3)
#endif
    }
}

int32_t encoder_count(uint8_t i) {
    int32_t v;
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE) { v = enc[i]; }
    return v;
}

#if SONARS
void sonar_trigger() {
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE) {
        echo_state = 1;
        CLK_TCCRB |= _BV(CLK_ICES);  // rising edge first
        CLK_TIFR = _BV(CLK_ICF);
        CLK_TIMSK |= _BV(CLK_ICIE);
    }
    SONAR_TRIG_PORT |= _BV(SONAR_TRIG_BIT);
    _delay_us(10);
    SONAR_TRIG_PORT &= ~_BV(SONAR_TRIG_BIT);
}

int16_t sonar_result() {
    if (echo_state != 3) return -2;
    echo_state = 0;
    return echo_ticks / 116;  // 58 us per cm, 2 ticks per us
}
#else
void sonar_trigger() {}
int16_t sonar_result() { return -1; }
#endif

uint16_t battery_mv() { return (uint32_t)battery_adc() * BATTERY_MV_FULL_SCALE / 1023; }

uint16_t battery_adc() {
    ADCSRA |= _BV(ADSC);
    while (ADCSRA & _BV(ADSC)) {
    }
    return ADC;
}
