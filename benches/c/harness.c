/* Instruction-count benchmark of postback_rx.c on QEMU netduinoplus2 (-icount shift=0),
 * measured the way benches/mcu/src/bin/qemu_bench.rs measures the Rust crate:
 *  - SysTick, clocked from the (virtual) 168 MHz core clock, counts the virtual clock, which
 *    -icount shift=0 advances 1 ns per guest instruction; a loop of known length (subs/bne)
 *    timed at 200,000 and 400,000 iterations calibrates instructions per tick (125/21);
 *  - amortized costs: a loop runs the body n and 2n times, the difference is divided by n
 *    and the loop's own overhead (the same loop with an empty body) is subtracted;
 *  - per-call costs: each call timed alone, minus an empty timed region, averaged;
 *  - a measurement during which SysTick wrapped (COUNTFLAG) aborts the run.
 * postback_rx.c is a separate translation unit (no LTO): every call is a real call, as from
 * a CAN receive interrupt. Output goes through semihosting; the exit status is 0 when every
 * correctness check passed. */
#include <stdint.h>
#include "postback_rx.h"

void semihost_write0(const char *s);
void semihost_exit(int ok);

/* ---- barriers ------------------------------------------------------------------------ */
#define BB(x) __asm__ volatile("" : "+r"(x))           /* value unknown to the compiler */
#define USE(x) __asm__ volatile("" : : "r"(x) : "memory") /* value needed, memory observed */
#define CLOBBER() __asm__ volatile("" : : : "memory")

/* ---- output ---------------------------------------------------------------------------- */
static char line[160];
static unsigned pos;

static void put(const char *s) { while (*s && pos < sizeof line - 1) line[pos++] = *s++; }
static void flush(void) { line[pos] = 0; semihost_write0(line); pos = 0; }

static void put_u(uint64_t v)
{
    char tmp[24];
    int n = 0;
    do { tmp[n++] = (char)('0' + v % 10); v /= 10; } while (v);
    while (n) { char c[2] = {tmp[--n], 0}; put(c); }
}

/* A value in thousandths, printed with one decimal. */
static void put_milli(int64_t m)
{
    if (m < 0) { put("-"); m = -m; }
    uint64_t tenths = ((uint64_t)m + 50) / 100;
    put_u(tenths / 10);
    put(".");
    put_u(tenths % 10);
}

static int failed;
static void fail(const char *what)
{
    put("CHECK FAILED: "); put(what); put("\n"); flush();
    failed = 1;
}

/* ---- SysTick meter --------------------------------------------------------------------- */
#define SYST_CSR (*(volatile uint32_t *)0xE000E010)
#define SYST_RVR (*(volatile uint32_t *)0xE000E014)
#define SYST_CVR (*(volatile uint32_t *)0xE000E018)
#define COUNTFLAG (1u << 16)

static uint64_t ipt_num = 1, ipt_den = 1; /* instructions per tick = num / den */
static uint32_t empty_ticks;              /* an empty timed region */
static int64_t loop_overhead_m;           /* milli-instructions per empty loop iteration */

/* Ticks spent in `body` (SysTick counts down). */
#define TICKS(out, body)                                              \
    do {                                                              \
        (void)SYST_CSR; /* reading clears COUNTFLAG */                \
        uint32_t s_ = SYST_CVR;                                       \
        CLOBBER();                                                    \
        body;                                                         \
        CLOBBER();                                                    \
        uint32_t e_ = SYST_CVR;                                       \
        if (SYST_CSR & COUNTFLAG) {                                   \
            fail("SysTick wrapped during a measurement");             \
            semihost_exit(0);                                         \
        }                                                             \
        (out) = s_ - e_;                                              \
    } while (0)

static int64_t to_milli(int64_t ticks)
{
    return ticks * (int64_t)ipt_num * 1000 / (int64_t)ipt_den;
}

typedef void (*loop_fn)(uint32_t count);

/* Milli-instructions per iteration of `run` (loop overhead included), from n and 2n. */
static int64_t per_iter(uint32_t n, loop_fn run)
{
    uint32_t t1, t2;
    TICKS(t1, run(n));
    TICKS(t2, run(2 * n));
    return to_milli((int64_t)t2 - (int64_t)t1) / n;
}

/* Milli-instructions per execution of the body, loop overhead subtracted. */
static int64_t per_op(uint32_t n, loop_fn run) { return per_iter(n, run) - loop_overhead_m; }

/* Exactly 2 * n + 1 instructions for n >= 1. */
__attribute__((noinline)) static void known_loop(uint32_t n)
{
    __asm__ volatile("1: subs %0, %0, #1\n\t bne 1b" : "+r"(n) : : "cc");
}

/* A benchmark loop: `body` runs `count` times with `i` the iteration number. */
#define LOOP(name, body)                                              \
    __attribute__((noinline)) static void name(uint32_t count)        \
    {                                                                 \
        for (uint32_t i = 0; i < count; i++) {                        \
            BB(i);                                                    \
            body;                                                     \
        }                                                             \
    }

/* ---- inputs ---------------------------------------------------------------------------- */
/* Four different valid postbacks (the same values as qemu_bench.rs: an X30, not tracking,
 * heading follow, pitch -15.00 deg * k, heading 90.00 deg * k, motor 1.00 deg * k). */
static uint8_t msgs[4][4][8];
static uint8_t foreign[8] = {0x0F, 0x03, 0, 0, 0, 0, 0, 0};
static uint8_t crc_buf[512];
static uint8_t cmd[8];

static void build_postback(uint8_t m[32], int16_t pitch, uint16_t heading, int16_t motor)
{
    for (int k = 0; k < 32; k++) m[k] = 0;
    m[0] = 0xEB; m[1] = 0x90; m[2] = 0x0C;
    m[12] = 0x21; m[13] = 0xFE; m[14] = 0x0F; m[15] = 0x01;
    m[16] = 1; /* X30 */
    m[17] = 0; /* not tracking */
    m[18] = 2; /* heading follow */
    m[19] = (uint8_t)pitch; m[20] = (uint8_t)((uint16_t)pitch >> 8);
    m[21] = (uint8_t)heading; m[22] = (uint8_t)(heading >> 8);
    m[23] = (uint8_t)motor; m[24] = (uint8_t)((uint16_t)motor >> 8);
    uint16_t crc = crc_fly16(m, 25);
    m[25] = (uint8_t)crc; /* low byte first */
    m[26] = (uint8_t)(crc >> 8);
}

/* ---- benchmark bodies ------------------------------------------------------------------ */
LOOP(run_empty, (void)0)

LOOP(run_message, {
    uint8_t (*m)[8] = msgs[i & 3];
    int r;
    r = on_frame(POSTBACK_CAN_ID, m[0]); USE(r);
    r = on_frame(POSTBACK_CAN_ID, m[1]); USE(r);
    r = on_frame(POSTBACK_CAN_ID, m[2]); USE(r);
    r = on_frame(POSTBACK_CAN_ID, m[3]); USE(r);
})

LOOP(run_foreign, {
    uint32_t id = CONTROL_CAN_ID;
    const uint8_t *d = foreign;
    BB(id); BB(d);
    int r = on_frame(id, d);
    USE(r);
})

LOOP(run_encode, {
    int type = 2;       /* pitch */
    int16_t value = -450; /* -45.0 deg x10 */
    uint8_t *out = cmd;
    BB(type); BB(value); BB(out);
    encode_angle(out, type, value);
    CLOBBER();
})

#define CRC_LOOP(name, len)                                            \
    LOOP(name, {                                                       \
        u8 *p = crc_buf;                                               \
        uint16_t n = (len);                                            \
        BB(p); BB(n);                                                  \
        uint16_t c = crc_fly16(p, n);                                  \
        USE(c);                                                        \
    })
CRC_LOOP(run_crc512, 512)
CRC_LOOP(run_crc256, 256)
CRC_LOOP(run_crc25, 25)

/* ---- correctness checks ---------------------------------------------------------------- */
static int same(const uint8_t *a, const uint8_t *b, int n)
{
    for (int k = 0; k < n; k++)
        if (a[k] != b[k]) return 0;
    return 1;
}

static void checks(void)
{
    static u8 check[] = "123456789";
    if (crc_fly16(check, 9) != 0x4B37) fail("crc_fly16(\"123456789\") != 0x4B37");
    /* the protocol notes' TCP reference vector (look down 90 deg): CRC 0x5E68, sent 68 5E. */
    static u8 tcp[24] = {0xEB, 0x90, 0x0A, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0x40, 0x88,
                         0x0F, 0x07, 0, 0, 0, 0, 0, 0, 0x68, 0x5E};
    if (crc_fly16(tcp, 22) != (tcp[22] | tcp[23] << 8)) fail("TCP reference vector CRC");

    static const uint8_t pitch45[8] = {0x0F, 0x08, 0x02, 0x3E, 0xFE, 0, 0, 0};
    static const uint8_t heading45[8] = {0x0F, 0x08, 0x01, 0xC2, 0x01, 0, 0, 0};
    static const uint8_t zoom10[8] = {0x0F, 0x08, 0x03, 0xE8, 0x03, 0, 0, 0};
    uint8_t out[8];
    encode_angle(out, 2, -450);
    if (!same(out, pitch45, 8)) fail("encode_angle pitch -45");
    encode_angle(out, 1, 450);
    if (!same(out, heading45, 8)) fail("encode_angle heading 45");
    encode_angle(out, 3, 1000);
    if (!same(out, zoom10, 8)) fail("encode_angle zoom 10x");

    for (int k = 0; k < 4; k++) {
        for (int f = 0; f < 4; f++) {
            int r = on_frame(POSTBACK_CAN_ID, msgs[k][f]);
            if (r != (f == 3)) fail("postback: completion on the wrong frame");
        }
        if (gimbal_status.gimbal_type != 1 || gimbal_status.tracking != 0 ||
            gimbal_status.control_mode != 2 || gimbal_status.pitch != -1500 * k ||
            gimbal_status.heading != 9000 * k || gimbal_status.motor_psi != 100 * k)
            fail("postback: parsed fields");
        if (on_frame(CONTROL_CAN_ID, msgs[k][0]) != 0) fail("foreign ID accepted");
    }
    /* A bad CRC completes nothing; a restart on EB 90 mid-message resynchronises. */
    uint8_t bad[8];
    for (int f = 0; f < 8; f++) bad[f] = msgs[1][3][f];
    bad[1] ^= 1; /* the CRC's low byte */
    on_frame(POSTBACK_CAN_ID, msgs[1][0]);
    on_frame(POSTBACK_CAN_ID, msgs[1][1]);
    on_frame(POSTBACK_CAN_ID, msgs[1][2]);
    if (on_frame(POSTBACK_CAN_ID, bad) != 0) fail("bad CRC accepted");
    on_frame(POSTBACK_CAN_ID, msgs[2][0]);
    on_frame(POSTBACK_CAN_ID, msgs[2][1]);
    int ok = 0;
    for (int f = 0; f < 4; f++) ok = on_frame(POSTBACK_CAN_ID, msgs[3][f]);
    if (!ok || gimbal_status.pitch != -4500) fail("restart on EB 90");
    if (on_frame(POSTBACK_CAN_ID, msgs[3][1]) != 0) fail("frame outside a message");
}

/* ---- report ---------------------------------------------------------------------------- */
static void row(const char *what, int64_t milli, const char *reference)
{
    put("| "); put(what); put(" | "); put_milli(milli); put(" | "); put(reference); put(" |\n");
    flush();
}

int main(void)
{
    SYST_CSR = 0;
    SYST_RVR = 0x00FFFFFF;
    SYST_CVR = 0;
    SYST_CSR = (1u << 2) | 1u; /* processor clock, enabled, no interrupt */

    for (int k = 0; k < 4; k++)
        build_postback(&msgs[k][0][0], (int16_t)(-1500 * k), (uint16_t)(9000 * k),
                       (int16_t)(100 * k));
    uint32_t x = 0x12345678;
    for (int k = 0; k < 512; k++) {
        x ^= x << 13; x ^= x >> 17; x ^= x << 5;
        crc_buf[k] = (uint8_t)x;
    }
    checks();

    /* Calibration. */
    TICKS(empty_ticks, (void)0);
    const uint32_t N = 200000;
    uint32_t t1, t2, a = N, b = 2 * N;
    BB(a); BB(b);
    TICKS(t1, known_loop(a));
    TICKS(t2, known_loop(b));
    ipt_num = 2 * (uint64_t)N;
    ipt_den = t2 - t1;
    loop_overhead_m = per_iter(4096, run_empty);

    put("c_bench: calibration ");
    put_u(ipt_num); put(" instructions in "); put_u(ipt_den);
    put(" SysTick ticks (125/21 per tick expected), loop overhead ");
    put_milli(loop_overhead_m); put(" per iteration, empty timed region ");
    put_u(empty_ticks); put(" ticks\n"); flush();

    const uint32_t MESSAGES = 512;
    int64_t message = per_op(MESSAGES, run_message);
    if (gimbal_status.pitch != -4500) fail("message loop: last message not parsed");

    /* Frame by frame: each call timed alone. */
    int64_t frame_ticks[4] = {0, 0, 0, 0};
    uint32_t completed = 0;
    for (uint32_t i = 0; i < MESSAGES; i++) {
        for (int k = 0; k < 4; k++) {
            const uint8_t *d = msgs[i & 3][k];
            uint32_t id = POSTBACK_CAN_ID, t;
            int r;
            BB(d); BB(id);
            TICKS(t, r = on_frame(id, d); USE(r));
            frame_ticks[k] += (int64_t)t - (int64_t)empty_ticks;
            completed += (uint32_t)r;
        }
    }
    if (completed != MESSAGES) fail("frame-by-frame: not every message completed");

    int64_t foreign_m = per_op(4096, run_foreign);
    int64_t encode_m = per_op(4096, run_encode);
    int64_t crc_long = per_op(64, run_crc512);
    int64_t crc_short = per_op(64, run_crc256);
    int64_t crc25 = per_op(256, run_crc25);

    put("\n| measurement (guest instructions) | C, measured | published reference |\n"
        "|---|---:|---:|\n");
    flush();
    row("per received postback frame, amortized", message / 4, "97.5");
    row("frame 0 (header)", to_milli(frame_ticks[0]) / MESSAGES, "27");
    row("frame 1", to_milli(frame_ticks[1]) / MESSAGES, "23");
    row("frame 2", to_milli(frame_ticks[2]) / MESSAGES, "23");
    row("frame 3 (CRC + parse)", to_milli(frame_ticks[3]) / MESSAGES, "317");
    row("one complete message (4 frames), amortized", message, "390");
    row("frame on a foreign ID", foreign_m, "6");
    row("encode one angle command (pitch -45 deg)", encode_m, "10");
    row("CRC (`crc_fly16`) per byte, marginal (512 vs 256 bytes)", (crc_long - crc_short) / 256,
        "11");
    row("CRC (`crc_fly16`) over 25 bytes", crc25, "");
    return failed;
}
