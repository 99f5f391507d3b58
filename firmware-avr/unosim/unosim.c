/*
 * unosim: omnibot's Arduino UNO firmware in simavr, in real time, with its UART on a pty.
 *
 *   unosim --board ROBOT.board [--range CM] [--encoders CPS] [--report] [--lockstep] [--heap ADDR] [--profile FILE] FIRMWARE.elf
 *
 * The ATmega328P (or the board file's `mcu`, the Mega's atmega2560) runs at 16 MHz, kept in step with the wall clock (never faster; on a busy host it
 * falls behind by at most 20 ms and then slips, so the firmware's time never races). Its USART0 is a pseudo-terminal
 * whose path is the first line on stdout; bytes from the host reach the UART paced at 115200 baud
 * (one byte per 10 bit times), the firmware's bytes leave at the pace of simavr's UART model.
 * The wiring is the robot's, read from firmware-avr/generated/<robot>.board (docs/uno.md):
 *   - motors: signed PWM duty from each L298 channel's OCR, COM bit and IN1/IN2 pins;
 *   - sonar: a falling edge on the trigger pin answers an echo pulse of 58 us per cm on ICP1
 *     (none while the range is negative);
 *   - encoders: single-channel edges at a rate per wheel (counts/s), set on stdin, or from the
 *     duties with --encoders CPS (CPS counts/s at full duty);
 *   - battery: ADC7 at 2500 mV (the pack at its nominal voltage).
 * The board file may name the chip (`mcu atmega2560`; default atmega328p) and its external interrupts'
 * pins (`extint PORT BIT`, INT0 first; default the UNO's D2 and D3), which the harness unhooks.
 * stdin lines: `range CM`, `wheels C1 C2 C3 C4` (counts/s), `counts C1 C2 C3 C4` (absolute counts the
 * encoders move to, one edge per 50 us at most: hardware in the loop), `battery MV` (ADC pin mV), `reset` (a
 * power cycle that keeps the EEPROM), `stats` (prints `stats LONGEST AWAKE ELAPSED PASSES`: the
 * longest main-loop pass, the cycles awake and elapsed and the passes since the last `stats`), `quit`.
 * With --report, stdout gets `pwm T_US D1 D2 D3 D4` whenever a duty changes.
 * With --profile FILE, the program counter is sampled every PROFILE_CYCLES cycles the CPU is awake
 * and FILE gets `BYTE_ADDRESS SAMPLES` lines on exit (benchmarks/uno_profile.py names the functions);
 * the stdin command `profile` starts the count anew.
 * With --lockstep (hardware in the loop), stdout also gets `t T_US` every 2 emulated milliseconds
 * and the emulator never runs more than 3 ms ahead of the last `sync T_US` on stdin: the physics
 * that answers with `sync` and `counts` sets the pace, so a busy host slows both alike.
 * On exit, stderr gets `stack BYTES`: the deepest stack the firmware reached (its free RAM is
 * painted with 0xAA at reset). With --heap ADDR (the ELF's __heap_start, where the paint begins) it is
 * the lowest byte the stack wrote; without it, the first eight painted bytes in a row from the top,
 * which an image built with -flto fools (its main() can keep untouched locals of inlined functions).
 */
#define _GNU_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <poll.h>
#include <pty.h>
#include <sys/prctl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include <simavr/avr_adc.h>
#include <simavr/avr_extint.h>
#include <simavr/avr_ioport.h>
#include <simavr/avr_uart.h>
#include <simavr/sim_avr.h>
#include <simavr/sim_elf.h>
#include <simavr/sim_time.h>

#define MOTORS_MAX 4

#define F_CPU 16000000UL
#define BAUD 115200
#define BYTE_CYCLES (F_CPU * 10 / BAUD)
#define ENCODER_TICK_US 50
#define FIFO 8192
#define MAX_LAG_US 20000.0 /* the emulated clock may lag the wall clock by this much, then it slips */

static avr_t *avr;
static int pty_master = -1;
static volatile sig_atomic_t quit;

static uint8_t in_buf[FIFO];
static size_t in_head, in_tail;  /* host -> UART */
static uint8_t out_buf[FIFO];
static size_t out_len;           /* UART -> host */
static int uart_xoff;
static avr_irq_t *uart_in;

/* the wiring (--board): per motor OCR, TCCR, COM bit, IN1 PORT and bit, IN2 PORT and bit */
static unsigned motor_map[MOTORS_MAX][7];
static int motors, encoders;
static struct { char port; int bit; } encoder_map[MOTORS_MAX], trigger_pin, echo_pin;
static int has_sonar, battery_adc = -1;
static char mcu[32] = "atmega328p";
#define EXTINT_MAX 8
static struct { char port; int bit; } extint_map[EXTINT_MAX] = {{'D', 2}, {'D', 3}};
static int extints = 2, extints_given;
static avr_irq_t *encoder_irq[MOTORS_MAX];
static double wheel_cps[MOTORS_MAX];
static double wheel_pos[MOTORS_MAX];
static long wheel_count[MOTORS_MAX];
static double model_cps;  /* --encoders: counts/s at full duty, 0 = rates from stdin */
static int counts_given;  /* `counts` on stdin: the encoders follow absolute counts (hardware in the loop) */
static long counts_target[MOTORS_MAX];
static int report;
static int lockstep;
static double synced_us;  /* --lockstep: the peer has caught up to here */
#define LOCKSTEP_AHEAD_US 3000.0  /* the longest the encoders go without news: below the firmware's 5 ms turnaround pause */
#define LOCKSTEP_PERIOD_US 2000
static int duty_last[MOTORS_MAX];

static int range_cm = -1;
/* main-loop passes: cycles awake between two sleeps (the firmware sleeps at the end of each pass) */
static avr_cycle_count_t awake, stretch, longest, stats_from;
static unsigned long passes;
static avr_irq_t *echo_irq;

/* --profile: program-counter samples while awake, by flash word */
#define PROFILE_CYCLES 17
#define PROFILE_WORDS 0x20000 /* 256 KB of flash (the ATmega2560's) */
static const char *profile_file;
static uint32_t profile_hits[PROFILE_WORDS];

static avr_cycle_count_t profile_tick(avr_t *a, avr_cycle_count_t when, void *param) {
    (void)param;
    if (a->state == cpu_Running) profile_hits[(a->pc >> 1) & (PROFILE_WORDS - 1)]++;
    return when + PROFILE_CYCLES;
}

static void profile_write(void) {
    FILE *f = profile_file ? fopen(profile_file, "w") : NULL;
    if (!f) return;
    for (int i = 0; i < PROFILE_WORDS; i++)
        if (profile_hits[i]) fprintf(f, "%d %u\n", 2 * i, profile_hits[i]);
    fclose(f);
}

static void on_signal(int sig) {
    (void)sig;
    quit = 1;
}

/* ---------------------------------------------------------------- UART */

static void uart_output(struct avr_irq_t *irq, uint32_t value, void *param) {
    (void)irq;
    (void)param;
    if (out_len < FIFO) out_buf[out_len++] = (uint8_t)value;
}

static void uart_xon(struct avr_irq_t *irq, uint32_t value, void *param) {
    (void)irq;
    (void)value;
    (void)param;
    uart_xoff = 0;
}

static void uart_xoff_cb(struct avr_irq_t *irq, uint32_t value, void *param) {
    (void)irq;
    (void)value;
    (void)param;
    uart_xoff = 1;
}

static int feeding;

/* one byte per 10 bit times at 115200 baud, as a real line delivers them */
static avr_cycle_count_t feed_byte(avr_t *a, avr_cycle_count_t when, void *param) {
    (void)a;
    (void)param;
    if (in_head == in_tail) {
        feeding = 0;
        return 0;
    }
    if (!uart_xoff) {
        avr_raise_irq(uart_in, in_buf[in_tail]);
        in_tail = (in_tail + 1) % FIFO;
    }
    return when + BYTE_CYCLES;
}

static void start_feeding(void) {
    if (!feeding && in_head != in_tail) {
        feeding = 1;
        avr_cycle_timer_register(avr, BYTE_CYCLES, feed_byte, NULL);
    }
}

/* ---------------------------------------------------------------- sonar */

static avr_cycle_count_t echo_fall(avr_t *a, avr_cycle_count_t when, void *param) {
    (void)a;
    (void)when;
    (void)param;
    avr_raise_irq(echo_irq, 0);
    return 0;
}

static avr_cycle_count_t echo_rise(avr_t *a, avr_cycle_count_t when, void *param) {
    (void)when;
    (void)param;
    avr_raise_irq(echo_irq, 1);
    avr_cycle_timer_register_usec(a, (uint32_t)range_cm * 58 + 29, echo_fall, NULL);
    return 0;
}

static void trigger_changed(struct avr_irq_t *irq, uint32_t value, void *param) {
    (void)param;
    if (irq->value && !value && range_cm >= 0)  /* end of the trigger pulse */
        avr_cycle_timer_register_usec(avr, 450, echo_rise, NULL);
}

/* ---------------------------------------------------------------- motors and encoders */

static int duty(int i) {
    const unsigned *m = motor_map[i];
    if (!(avr->data[m[1]] & (1 << m[2]))) return 0;
    int in1 = (avr->data[m[3]] >> m[4]) & 1, in2 = (avr->data[m[5]] >> m[6]) & 1;
    int d = avr->data[m[0]];
    return in1 && !in2 ? d : (in2 && !in1 ? -d : 0);
}

static avr_cycle_count_t encoder_tick(avr_t *a, avr_cycle_count_t when, void *param) {
    (void)param;
    int changed = 0;
    for (int i = 0; i < motors; i++) {
        int d = duty(i);
        if (d != duty_last[i]) changed = 1;
        duty_last[i] = d;
        long target;
        if (counts_given) {
            target = counts_target[i];
        } else {
            double cps = model_cps > 0 ? model_cps * d / 255.0 : wheel_cps[i];
            wheel_pos[i] += cps * ENCODER_TICK_US * 1e-6;
            target = (long)floor(wheel_pos[i]);
        }
        if (target != wheel_count[i] && i < encoders) {  /* one edge per tick at most: the pin must be seen to change */
            wheel_count[i] += target > wheel_count[i] ? 1 : -1;
            avr_raise_irq(encoder_irq[i], wheel_count[i] & 1);
        }
    }
    if (lockstep && (when / avr_usec_to_cycles(a, ENCODER_TICK_US)) % (LOCKSTEP_PERIOD_US / ENCODER_TICK_US) == 0) {
        printf("t %llu\n", (unsigned long long)avr_cycles_to_usec(a, when));
        fflush(stdout);
    }
    if (changed && report) {
        printf("pwm %llu", (unsigned long long)avr_cycles_to_usec(a, when));
        for (int i = 0; i < motors; i++) printf(" %d", duty_last[i]);
        printf("\n");
        fflush(stdout);
    }
    return when + avr_usec_to_cycles(a, ENCODER_TICK_US);
}

/* The external interrupts' pins are motor or free pins the firmware never uses as interrupts; simavr
 * 1.6 polls a low level on them every cycle whatever the mode, which would slow the emulation tenfold. */
static void unhook_extints(void) {
    for (int i = 0; i < extints; i++) {
        avr_irq_t *pin = avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ(extint_map[i].port), extint_map[i].bit);
        avr_irq_t *ext = avr_io_getirq(avr, AVR_IOCTL_EXTINT_GETIRQ(), EXTINT_IRQ_OUT_INT0 + i);
        if (pin && ext) avr_unconnect_irq(pin, ext);
    }
}

/* ---------------------------------------------------------------- host side */

static void command(char *line) {
    int a[MOTORS_MAX];
    if (sscanf(line, "range %d", &a[0]) == 1) {
        range_cm = a[0];
    } else if (sscanf(line, "wheels %d %d %d %d", &a[0], &a[1], &a[2], &a[3]) == 4) {
        for (int i = 0; i < MOTORS_MAX; i++) wheel_cps[i] = a[i];
    } else if (sscanf(line, "counts %ld %ld %ld %ld", &counts_target[0], &counts_target[1], &counts_target[2],
                      &counts_target[3]) == 4) {
        counts_given = 1;
    } else if (sscanf(line, "sync %lf", &synced_us) == 1) {
        /* the peer's time: the emulator may run up to LOCKSTEP_AHEAD_US past it */
    } else if (sscanf(line, "battery %d", &a[0]) == 1 && battery_adc >= 0) {
        avr_raise_irq(avr_io_getirq(avr, AVR_IOCTL_ADC_GETIRQ, ADC_IRQ_ADC0 + battery_adc), a[0]);
    } else if (strncmp(line, "reset", 5) == 0) {
        avr_reset(avr);  /* a power cycle: RAM and registers start over, the EEPROM keeps its bytes */
        unhook_extints();
    } else if (strncmp(line, "stats", 5) == 0) {
        /* cycles: longest pass, awake in all, elapsed; then the passes; and start counting anew */
        printf("stats %llu %llu %llu %lu\n", (unsigned long long)longest, (unsigned long long)awake,
               (unsigned long long)(avr->cycle - stats_from), passes);
        fflush(stdout);
        longest = awake = 0;
        passes = 0;
        stats_from = avr->cycle;
    } else if (strncmp(line, "profile", 7) == 0) {
        memset(profile_hits, 0, sizeof profile_hits);
    } else if (strncmp(line, "quit", 4) == 0) {
        quit = 1;
    } else {
        fprintf(stderr, "unosim: unknown command: %s", line);
    }
}

static int stdin_open = 1;
static char stdin_line[256];
static size_t stdin_len;

static void read_stdin(void) {
    char buf[256];
    ssize_t n = read(0, buf, sizeof buf);
    if (n <= 0) {
        stdin_open = 0;  /* no more commands; the emulator runs on */
        return;
    }
    for (ssize_t i = 0; i < n; i++) {
        if (stdin_len < sizeof stdin_line - 1) stdin_line[stdin_len++] = buf[i];
        if (buf[i] == '\n') {
            stdin_line[stdin_len] = 0;
            command(stdin_line);
            stdin_len = 0;
        }
    }
}

static size_t fifo_room(void) { return (in_tail + FIFO - in_head - 1) % FIFO; }

/* Only as many bytes as the FIFO takes: a host far ahead of the line finds the pty full and waits,
 * as it would for a real serial port (bytes read and then dropped were lost on the line). */
static void read_pty(void) {
    uint8_t buf[512];
    size_t room = fifo_room();
    ssize_t n = read(pty_master, buf, room < sizeof buf ? room : sizeof buf);
    for (ssize_t i = 0; i < n; i++) {
        in_buf[in_head] = buf[i];
        in_head = (in_head + 1) % FIFO;
    }
    start_feeding();
}

static void write_pty(void) {
    size_t done = 0;
    while (done < out_len) {
        ssize_t n = write(pty_master, out_buf + done, out_len - done);
        if (n <= 0) break;  /* nobody reading: keep it for later */
        done += (size_t)n;
    }
    memmove(out_buf, out_buf + done, out_len - done);
    out_len -= done;
}

static int read_board(const char *path) {
    FILE *f = fopen(path, "r");
    if (!f) {
        perror(path);
        return -1;
    }
    char line[256], port;
    unsigned m[7];
    int bit, ok = 1;
    while (ok && fgets(line, sizeof line, f)) {
        if (line[0] == '#' || line[0] == '\n') continue;
        if (sscanf(line, "motor %x %x %u %x %u %x %u", &m[0], &m[1], &m[2], &m[3], &m[4], &m[5], &m[6]) == 7 &&
            motors < MOTORS_MAX)
            memcpy(motor_map[motors++], m, sizeof m);
        else if (sscanf(line, "encoder %c %d", &port, &bit) == 2 && encoders < MOTORS_MAX) {
            encoder_map[encoders].port = port;
            encoder_map[encoders++].bit = bit;
        } else if (sscanf(line, "trigger %c %d", &port, &bit) == 2) {
            trigger_pin.port = port;
            trigger_pin.bit = bit;
            has_sonar |= 1;
        } else if (sscanf(line, "echo %c %d", &port, &bit) == 2) {
            echo_pin.port = port;
            echo_pin.bit = bit;
            has_sonar |= 2;
        } else if (sscanf(line, "mcu %31s", mcu) == 1) {
        } else if (sscanf(line, "extint %c %d", &port, &bit) == 2) {
            if (!extints_given) extints = 0;
            extints_given = 1;
            if (extints < EXTINT_MAX) {
                extint_map[extints].port = port;
                extint_map[extints++].bit = bit;
            }
        } else if (sscanf(line, "battery %d", &battery_adc) != 1) {
            fprintf(stderr, "unosim: %s: cannot read: %s", path, line);
            ok = 0;
        }
    }
    fclose(f);
    return ok && motors ? 0 : -1;
}

static double wall_us(const struct timespec *start) {
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    return (now.tv_sec - start->tv_sec) * 1e6 + (now.tv_nsec - start->tv_nsec) / 1e3;
}

static void no_sleep(avr_t *a, avr_cycle_count_t how_long) {
    (void)a;
    (void)how_long;  /* the main loop keeps the emulator in step with the wall clock */
}

static int heap_start = -1;  /* --heap: the data address where the firmware's paint begins */

/* From the paint's start up, the first byte the stack wrote; without --heap, from the top of RAM
 * down, the first eight painted bytes in a row: the stack never reached them. */
static int stack_depth(void) {
    if (heap_start >= 0x100 && heap_start <= avr->ramend) {
        int addr = heap_start;
        while (addr <= avr->ramend && avr->data[addr] == 0xAA) addr++;
        return avr->ramend - addr + 1;
    }
    int run = 0;
    for (int addr = avr->ramend; addr >= 0x100; addr--) {
        run = avr->data[addr] == 0xAA ? run + 1 : 0;
        if (run == 8) return avr->ramend - (addr + 7);
    }
    return -1;
}

int main(int argc, char **argv) {
    const char *elf = NULL, *board = NULL;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--board") && i + 1 < argc) board = argv[++i];
        else if (!strcmp(argv[i], "--range") && i + 1 < argc) range_cm = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--encoders") && i + 1 < argc) model_cps = atof(argv[++i]);
        else if (!strcmp(argv[i], "--report")) report = 1;
        else if (!strcmp(argv[i], "--lockstep")) lockstep = report = 1;
        else if (!strcmp(argv[i], "--profile") && i + 1 < argc) profile_file = argv[++i];
        else if (!strcmp(argv[i], "--heap") && i + 1 < argc) heap_start = (int)strtol(argv[++i], NULL, 0);
        else if (argv[i][0] != '-' && !elf) elf = argv[i];
        else {
            elf = NULL;
            break;
        }
    }
    if (!elf || !board) {
        fprintf(stderr, "usage: unosim --board ROBOT.board [--range CM] [--encoders CPS] [--report] [--lockstep] [--heap ADDR] [--profile FILE] FIRMWARE.elf\n");
        return 2;
    }
    if (read_board(board) != 0) {
        fprintf(stderr, "unosim: %s is not a board file (firmware-avr/generated/<robot>.board)\n", board);
        return 2;
    }
    elf_firmware_t fw;
    memset(&fw, 0, sizeof fw);
    int saved_stdout = dup(1), devnull = open("/dev/null", O_WRONLY);
    dup2(devnull, 1);  /* simavr's loader talks on stdout, which carries the pty path */
    int loaded = elf_read_firmware(elf, &fw);
    if (loaded != 0) {
        fprintf(stderr, "unosim: cannot read %s\n", elf);
        return 1;
    }
    avr = avr_make_mcu_by_name(mcu);
    if (!avr) {
        fprintf(stderr, "unosim: simavr has no mcu %s\n", mcu);
        return 1;
    }
    avr_init(avr);
    avr->frequency = F_CPU;
    avr->avcc = avr->vcc = avr->aref = 5000;
    avr->log = 0;
    avr_load_firmware(avr, &fw);
    fflush(stdout);
    dup2(saved_stdout, 1);
    close(saved_stdout);
    close(devnull);
    avr->sleep = no_sleep;
    unhook_extints();

    uint32_t flags = 0;
    avr_ioctl(avr, AVR_IOCTL_UART_GET_FLAGS('0'), &flags);
    flags &= ~(AVR_UART_FLAG_STDIO | AVR_UART_FLAG_POLL_SLEEP);
    avr_ioctl(avr, AVR_IOCTL_UART_SET_FLAGS('0'), &flags);
    uart_in = avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_INPUT);
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUTPUT), uart_output, NULL);
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUT_XON), uart_xon, NULL);
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUT_XOFF), uart_xoff_cb, NULL);

    if (has_sonar == 3) {
        echo_irq = avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ(echo_pin.port), echo_pin.bit);
        avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ(trigger_pin.port), trigger_pin.bit),
                                trigger_changed, NULL);
    }
    for (int i = 0; i < encoders; i++)
        encoder_irq[i] = avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ(encoder_map[i].port), encoder_map[i].bit);
    if (battery_adc >= 0)
        avr_raise_irq(avr_io_getirq(avr, AVR_IOCTL_ADC_GETIRQ, ADC_IRQ_ADC0 + battery_adc), 2500);
    avr_cycle_timer_register_usec(avr, ENCODER_TICK_US, encoder_tick, NULL);
    if (profile_file) avr_cycle_timer_register(avr, PROFILE_CYCLES, profile_tick, NULL);

    int slave;
    if (openpty(&pty_master, &slave, NULL, NULL, NULL) != 0) {
        perror("unosim: openpty");
        return 1;
    }
    struct termios tio;
    tcgetattr(slave, &tio);
    cfmakeraw(&tio);
    tcsetattr(slave, TCSANOW, &tio);
    fcntl(pty_master, F_SETFL, fcntl(pty_master, F_GETFL) | O_NONBLOCK);
    printf("%s\n", ttyname(slave));
    fflush(stdout);

    prctl(PR_SET_PDEATHSIG, SIGTERM);  /* ends with the process that started it */
    signal(SIGTERM, on_signal);
    signal(SIGINT, on_signal);
    signal(SIGPIPE, SIG_IGN);

    struct timespec start;
    clock_gettime(CLOCK_MONOTONIC, &start);
    int rc = 0;
    double slip_us = 0;
    while (!quit) {
        /* run until 1 ms ahead of the wall clock (or 20000 steps, to keep the I/O responsive) */
        double until_us = wall_us(&start) - slip_us + 1000;
        if (lockstep && until_us > synced_us + LOCKSTEP_AHEAD_US) until_us = synced_us + LOCKSTEP_AHEAD_US;
        for (int i = 0; i < 20000 && avr_cycles_to_usec(avr, avr->cycle) < until_us; i++) {
            avr_cycle_count_t before = avr->cycle;
            int state = avr_run(avr);
            if (state == cpu_Running) {
                awake += avr->cycle - before;
                stretch += avr->cycle - before;
            } else if (stretch) {  /* the main loop went to sleep: one pass ended */
                if (stretch > longest) longest = stretch;
                passes++;
                stretch = 0;
            }
            if (state == cpu_Done || state == cpu_Crashed) {
                fprintf(stderr, "unosim: the firmware %s\n", state == cpu_Done ? "stopped" : "crashed");
                quit = 1;
                rc = 1;
                break;
            }
        }
        if (out_len) write_pty();
        double ahead_us = avr_cycles_to_usec(avr, avr->cycle) - (wall_us(&start) - slip_us);
        if (lockstep && ahead_us < 0) {  /* held back by the peer: that is the pace, not a lag */
            slip_us += -ahead_us;
            ahead_us = 0;
        } else if (ahead_us < -MAX_LAG_US) {  /* fell behind (a busy host): slip, never race to catch up */
            slip_us += -MAX_LAG_US - ahead_us;
            ahead_us = -MAX_LAG_US;
        }
        int timeout_ms = ahead_us > 0 ? (int)(ahead_us / 1000) : 0;
        if (lockstep && avr_cycles_to_usec(avr, avr->cycle) >= synced_us + LOCKSTEP_AHEAD_US)
            timeout_ms = 1;  /* waiting for the peer's sync */
        struct pollfd fds[2] = {{pty_master, fifo_room() ? POLLIN : 0, 0}, {0, POLLIN, 0}};
        if (poll(fds, stdin_open ? 2 : 1, timeout_ms) > 0) {
            if (fds[0].revents & POLLIN) read_pty();
            if (fds[1].revents & (POLLIN | POLLHUP)) read_stdin();
        }
    }
    fprintf(stderr, "time emulated %.0f us, wall %.0f us, slipped %.0f us\n", (double)avr_cycles_to_usec(avr, avr->cycle), wall_us(&start), slip_us);
    fprintf(stderr, "stack %d\n", stack_depth());
    profile_write();
    close(slave);
    close(pty_master);
    return rc;
}
