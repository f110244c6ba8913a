/*
 * The paper's free-ball scene from C, on a Cortex-M4F (QEMU -M mps2-an386), through the C API
 * of absorber-core (absorber-ffi/include/absorber.h, libabsorber_ffi.a).
 *
 * It runs what the Rust firmware fw-free runs (Params default, at rest, 6667 steps of 3 ms with
 * the base acceleration -A w^2 sin(w k h), A = 0.5 mm, w = 2 pi 4.13 Hz, in float) and folds every
 * step's report and full state into the same 64-bit FNV-1a fingerprint; then it runs it again
 * with the on-device monitor recording after every step, as fw-free-monitor does. The Rust
 * fingerprints are passed on the command line (expect=0x... expect-monitor=0x...): the exit code
 * is 0 only if both are reproduced bit for bit (1 on a mismatch, 2 without references, 3 if the
 * model cannot start, 4 if a bad parameter is not refused with its value).
 * scripts/c-example.sh builds and checks it.
 */
#include <stddef.h>
#include <stdint.h>

#include "absorber.h"
#include "semihosting.h"

#define STEPS 6667u   /* ceil(20 s / 3 ms) */
#define STEP_MS 3u

/* The model and the monitor live in caller storage: no heap. */
static _Alignas(ABSORBER_MODEL_ALIGN) unsigned char model_storage[ABSORBER_MODEL_SIZE_FREE_N3_F32];
static _Alignas(ABSORBER_MODEL_ALIGN) unsigned char monitor_storage[ABSORBER_MONITOR_SIZE_F32];

/* ---- output without a C library ------------------------------------------------------------ */

static char line[160];
static size_t pos;

static void put(const char *s)
{
    while (*s && pos + 1 < sizeof line) {
        line[pos++] = *s++;
    }
}

static void put_u64(uint64_t x)
{
    char d[21];
    int n = 0;
    do {
        d[n++] = (char)('0' + x % 10);
        x /= 10;
    } while (x);
    while (n) {
        char c[2] = {d[--n], 0};
        put(c);
    }
}

static void put_hex(uint64_t x, int digits)
{
    put("0x");
    for (int i = digits - 1; i >= 0; i--) {
        char c[2] = {"0123456789abcdef"[(x >> (4 * i)) & 0xf], 0};
        put(c);
    }
}

static void flush(void)
{
    line[pos++] = '\n';
    line[pos] = 0;
    sh_write(line);
    pos = 0;
}

/* ---- the fingerprint of absorber_firmware::run ---------------------------------------------- */

static uint64_t hash;

static void word(uint32_t w)
{
    for (int i = 0; i < 4; i++) {
        hash ^= (w >> (8 * i)) & 0xffu;
        hash *= 0x00000100000001b3ull;
    }
}

static uint32_t bits(float x)
{
    union {
        float f;
        uint32_t u;
    } v = {x};
    return v.u;
}

/* Base acceleration at the end of step k [m/s^2], as absorber_firmware::base_accel (float, the
   Rust references' sine). Needs -ffp-contract=off: no fused multiply-add. */
static float base_accel(uint32_t k, float h)
{
    const float omega = 2.0f * 3.14159265358979323846f * 4.13f;
    const float t = (float)k * h;
    return -0.5e-3f * omega * omega * absorber_sinf(omega * t);
}

struct summary {
    uint64_t hash;
    uint32_t impacts, iterations, errors;
};

/* Runs STEPS steps of the model (and records into the monitor if given). */
static struct summary run(AbsorberModel *m, AbsorberMonitor *mon, float h)
{
    static float q[ABSORBER_MAX_DOFS], v[ABSORBER_MAX_DOFS], a[ABSORBER_MAX_DOFS];
    struct summary s = {0, 0, 0, 0};
    uint32_t record_errors = 0;
    hash = 0xcbf29ce484222325ull;
    for (uint32_t k = 1; k <= STEPS; k++) {
        const float accel = base_accel(k, h);
        AbsorberReportF32 r;
        if (absorber_step_f32(m, accel, &r) == ABSORBER_STATUS_OK) {
            s.iterations += r.iterations;
            word(r.iterations);
            word(bits(r.increment));
            word(r.work);
            word(r.outcome);
            if (r.impact) {
                s.impacts++;
                word(bits(r.impact_time));
                word(bits(r.impact_relative_speed));
                word(bits(r.impact_impulse));
                word(bits(r.impact_energy_loss));
                word(r.impact_stuck);
            }
            if (mon && absorber_monitor_record_f32(mon, m, &r, accel, NULL) != ABSORBER_STATUS_OK) {
                record_errors++;
            }
        } else {
            s.errors++;
            word(0xdead0000u | s.errors);
        }
        AbsorberStateInfoF32 info;
        absorber_state_f32(m, &info, q, v, a, ABSORBER_MAX_DOFS);
        for (const float *x = q; x < q + info.dofs; x++) word(bits(*x));
        for (const float *x = v; x < v + info.dofs; x++) word(bits(*x));
        for (const float *x = a; x < a + info.dofs; x++) word(bits(*x));
        word(bits(info.time));
        word(bits(info.base_accel));
        /* The firmware's contact words: 0 on the track, 1 / 2 on the positive / negative stop,
         * 3 in flight followed by the ball's centre and velocity, 4 beyond the stops. */
        word(info.contact == 0   ? 0u
             : info.contact == 1 ? 1u
             : info.contact == 2 ? 3u
             : info.contact == 3 ? 4u
                                 : 2u);
        if (info.contact == 2) {
            for (int i = 0; i < 2; i++) word(bits(info.ball_centre[i]));
            for (int i = 0; i < 2; i++) word(bits(info.ball_velocity[i]));
        }
        if (mon) {
            AbsorberMonitorReadingF32 r;
            absorber_monitor_read_f32(mon, &r);
            word(bits(r.root_stress));
            word(bits(r.closed_damage));
            word(bits(r.closed_cycles));
            word(bits(r.closed_max_range));
            word((uint32_t)r.reversals);
            word((uint32_t)(r.reversals >> 32));
            word(r.residue_len);
            word((uint32_t)(r.overflows ^ (r.overflows >> 32)));
            word((uint32_t)r.samples);
            word(r.rejected);
            word(r.impacts);
            word(record_errors);
            if ((k * STEP_MS) / 1000 != ((k - 1) * STEP_MS) / 1000) {
                const float every_second[] = {r.root_stress, r.damage,  r.equivalent_range,
                                              r.cycles,      r.max_range, r.tip_rms,
                                              r.tip_peak,    r.ball_rms, r.beam_energy,
                                              r.ball_energy};
                for (size_t i = 0; i < sizeof every_second / sizeof *every_second; i++) {
                    word(bits(every_second[i]));
                }
            }
        }
    }
    s.hash = hash;
    return s;
}

/* ---- command line --------------------------------------------------------------------------- */

static int parse_hex(const char *s, uint64_t *out)
{
    uint64_t x = 0;
    int n = 0;
    if (s[0] == '0' && s[1] == 'x') s += 2;
    for (; *s && *s != ' '; s++, n++) {
        const char c = *s;
        const int d = c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10 : -1;
        if (d < 0) return 0;
        x = x << 4 | (uint64_t)d;
    }
    *out = x;
    return n > 0;
}

static int arg(const char *cmdline, const char *key, uint64_t *out)
{
    for (const char *p = cmdline; *p; p++) {
        if (p != cmdline && p[-1] != ' ') continue;
        const char *k = key, *q = p;
        while (*k && *q == *k) k++, q++;
        if (!*k) return parse_hex(q, out);
    }
    return 0;
}

static void report(const char *what, struct summary s)
{
    put(what);
    put(" impacts=");
    put_u64(s.impacts);
    put(" iterations=");
    put_u64(s.iterations);
    put(" errors=");
    put_u64(s.errors);
    flush();
}

/* A bad parameter is refused with its name, the allowed range and the value given, as a double
   (the library formats no floats): here a negative Young's modulus. A function of its own, so
   that its copy of the parameters is not in main's frame during the boot-stack measurement. */
static __attribute__((noinline)) int bad_parameter_is_reported(const AbsorberParams *p)
{
    AbsorberParams bad = *p;
    bad.beam.modulus = -2.0e11;
    AbsorberModel *m;
    AbsorberError err;
    const AbsorberStatus s = absorber_init(model_storage, sizeof model_storage,
                                           ABSORBER_VARIANT_FREE_N3_F32, &bad, 0.0, &m, &err);
    const int ok = s == ABSORBER_STATUS_INVALID_PARAMETER && err.has_value == 1 &&
                   err.value == -2.0e11;
    put("bad parameter: ");
    put(err.field);
    put(" ");
    put(err.reason);
    put(ok ? ", value -2e11 reported" : ", WRONG value or status");
    flush();
    return ok;
}

int main(void)
{
    static char cmdline[256];
    if (sh_cmdline(cmdline, sizeof cmdline) != 0) cmdline[0] = 0;

    AbsorberParams p;
    absorber_params_default(&p);
    /* The firmware's defaults (docs/embedded.md): every event at the end of its step, and the
       work cap that bounds every step to twice the mean. */
    p.integrator.events = ABSORBER_EVENTS_STEP_END;
    p.max_work = ABSORBER_WORK_DEADLINE;
    const float h = (float)p.integrator.step;
    AbsorberModel *m;
    AbsorberError err;
    if (absorber_init(model_storage, sizeof model_storage, ABSORBER_VARIANT_FREE_N3_F32, &p, 0.0,
                      &m, &err) != ABSORBER_STATUS_OK) {
        put("init failed: ");
        put(err.field);
        put(": ");
        put(err.reason);
        flush();
        return 3;
    }
    /* The boot stack from reset: the high-water mark through the model's construction. */
    put("# boot stack from reset, absorber_init = ");
    put_u64(stack_used());
    put(" bytes");
    flush();
    put("scene free ball, N = 3, float, from C: ");
    put_u64(STEPS);
    put(" steps of 3 ms, model storage ");
    put_u64(absorber_model_size(ABSORBER_VARIANT_FREE_N3_F32));
    put(" bytes");
    flush();
    const struct summary free = run(m, NULL, h);
    report("free:", free);
    put("state_hash=");
    put_hex(free.hash, 16);
    flush();

    /* The same scene with the monitor (fw-free-monitor), its boot stack measured afresh: the
       stack is painted again, so the run above does not count. */
    AbsorberMonitor *mon;
    stack_paint();
    if (absorber_init(model_storage, sizeof model_storage, ABSORBER_VARIANT_FREE_N3_F32, &p, 0.0,
                      &m, &err) != ABSORBER_STATUS_OK ||
        absorber_monitor_init(monitor_storage, sizeof monitor_storage, m, NULL, &mon, &err) !=
            ABSORBER_STATUS_OK) {
        put("monitor init failed: ");
        put(err.field);
        flush();
        return 3;
    }
    put("# boot stack from reset, absorber_init + absorber_monitor_init = ");
    put_u64(stack_used());
    put(" bytes");
    flush();
    const struct summary monitored = run(m, mon, h);
    report("free + monitor:", monitored);
    put("monitor_state_hash=");
    put_hex(monitored.hash, 16);
    flush();

    if (!bad_parameter_is_reported(&p)) return 4;

    uint64_t expect = 0, expect_monitor = 0;
    const int have = arg(cmdline, "expect=", &expect);
    const int have_monitor = arg(cmdline, "expect-monitor=", &expect_monitor);
    if (!have && !have_monitor) {
        put("# no reference given (expect=0x<fw-free state_hash> expect-monitor=0x<fw-free-monitor state_hash>)");
        flush();
        return 2;
    }
    int ok = 1;
    if (have) ok &= expect == free.hash;
    if (have_monitor) ok &= expect_monitor == monitored.hash;
    put(ok ? "# matches the Rust firmware bit for bit" : "# MISMATCH with the Rust firmware");
    flush();
    return ok ? 0 : 1;
}
