/*
 * The cost of a step through the FMU against the same step through the C API, as an importer
 * pays it: the FMU's shared library is loaded with dlopen and called through the function types
 * of the standard's fmi3Functions.h; the C API is linked statically (libabsorber_ffi.a).
 *
 *   overhead capi N [read]                       N steps: absorber_step_f64 + absorber_monitor_record_f64
 *   overhead fmu  N LIB TOKEN RESOURCES [read|load]   N steps: fmi3SetFloat64 (input) + fmi3DoStep (one h)
 *
 * Both run the paper's scene (free ball, 3 elements, f64, h = 3 ms) under the paper's harmonic
 * base acceleration (0.5 mm at 4.13 Hz) with the monitor (root stress, rainflow, Miner damage):
 * the same model, bit for bit. With `read`, each step also reads the outputs (tip deflection,
 * root stress, damage: absorber_outputs_f64 + absorber_monitor_read_f64, or one fmi3GetFloat64).
 * With `load`, the FMU also gets a small tip load (0.01 N), which the C API has no input for:
 * the FMU then steps the loaded scene (the loads' terms in every residual).
 * scripts/fmu-overhead.sh counts the instructions of N and of 0 steps under valgrind and takes
 * the difference per step. Prints a checksum of the outputs so nothing is optimized away.
 */
#include <dlfcn.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "absorber.h"
#include "fmi3Functions.h"

static double accel(long k) {
    const double w = 2.0 * 3.14159265358979323846 * 4.13;
    return -0.5e-3 * w * w * sin(w * (double)k * 0.003);
}

static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category,
                   fmi3String message) {
    (void)env;
    fprintf(stderr, "fmu [%d %s] %s\n", (int)status, category, message);
}

static int capi(long n, int read) {
    static _Alignas(ABSORBER_MODEL_ALIGN) unsigned char model_storage[ABSORBER_MODEL_SIZE_FREE_N3_F64];
    static _Alignas(ABSORBER_MODEL_ALIGN) unsigned char monitor_storage[ABSORBER_MONITOR_SIZE_F64];
    AbsorberParams p;
    absorber_params_default(&p);
    AbsorberModel *m;
    AbsorberMonitor *mon;
    AbsorberError err;
    if (absorber_init(model_storage, sizeof model_storage, ABSORBER_VARIANT_FREE_N3_F64, &p, 0.0, &m,
                      &err) != ABSORBER_STATUS_OK ||
        absorber_monitor_init(monitor_storage, sizeof monitor_storage, m, NULL, &mon, &err) !=
            ABSORBER_STATUS_OK) {
        fprintf(stderr, "init: %s: %s\n", err.field, err.reason);
        return 1;
    }
    double sum = 0.0;
    for (long k = 1; k <= n; k++) {
        const double a = accel(k);
        AbsorberReportF64 r;
        double stress;
        if (absorber_step_f64(m, a, &r) != ABSORBER_STATUS_OK ||
            absorber_monitor_record_f64(mon, m, &r, a, &stress) != ABSORBER_STATUS_OK) {
            fprintf(stderr, "step %ld failed\n", k);
            return 1;
        }
        if (read) {
            AbsorberOutputsF64 o;
            AbsorberMonitorReadingF64 q;
            absorber_outputs_f64(m, &o);
            absorber_monitor_read_f64(mon, &q);
            sum += o.tip_deflection + q.root_stress * 1e-9 + q.damage;
        }
    }
    AbsorberOutputsF64 o;
    absorber_outputs_f64(m, &o);
    printf("capi: %ld steps, tip deflection %.17g, checksum %.17g\n", n, o.tip_deflection, sum);
    return 0;
}

#define LOAD(name) name##TYPE *name = (name##TYPE *)dlsym(lib, #name)

static int fmu(long n, const char *path, const char *token, const char *resources, int read,
               int load) {
    void *lib = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        fprintf(stderr, "dlopen: %s\n", dlerror());
        return 1;
    }
    LOAD(fmi3InstantiateCoSimulation);
    LOAD(fmi3EnterInitializationMode);
    LOAD(fmi3ExitInitializationMode);
    LOAD(fmi3SetFloat64);
    LOAD(fmi3GetFloat64);
    LOAD(fmi3DoStep);
    LOAD(fmi3FreeInstance);
    if (!fmi3InstantiateCoSimulation || !fmi3DoStep || !fmi3SetFloat64 || !fmi3GetFloat64) {
        fprintf(stderr, "missing FMI 3 functions\n");
        return 1;
    }
    fmi3Instance fmu = fmi3InstantiateCoSimulation("overhead", token, resources, fmi3False, fmi3False,
                                                   fmi3False, fmi3False, NULL, 0, NULL, logger, NULL);
    if (!fmu || fmi3EnterInitializationMode(fmu, fmi3False, 0.0, 0.0, fmi3False, 0.0) != fmi3OK ||
        fmi3ExitInitializationMode(fmu) != fmi3OK) {
        fprintf(stderr, "instantiate/initialize failed\n");
        return 1;
    }
    const double h = 0.003;
    const fmi3ValueReference inputs[2] = {1, 2}; /* base_acceleration, tip_load */
    const fmi3ValueReference outputs[3] = {10, 12, 16}; /* tip_deflection, root_stress, damage */
    double sum = 0.0, y[3];
    for (long k = 1; k <= n; k++) {
        const double u[2] = {accel(k), load ? 0.01 * sin(0.5 * (double)k * h) : 0.0};
        fmi3Boolean event, terminate, early;
        fmi3Float64 last;
        if (fmi3SetFloat64(fmu, inputs, (size_t)(1 + load), u, (size_t)(1 + load)) != fmi3OK ||
            fmi3DoStep(fmu, (double)(k - 1) * h, h, fmi3True, &event, &terminate, &early, &last) !=
                fmi3OK) {
            fprintf(stderr, "step %ld failed\n", k);
            return 1;
        }
        if (read) {
            fmi3GetFloat64(fmu, outputs, 3, y, 3);
            sum += y[0] + y[1] * 1e-9 + y[2];
        }
    }
    fmi3GetFloat64(fmu, outputs, 3, y, 3);
    printf("fmu:  %ld steps, tip deflection %.17g, checksum %.17g\n", n, y[0], sum);
    fmi3FreeInstance(fmu);
    return 0;
}

int main(int argc, char **argv) {
    if (argc >= 3 && strcmp(argv[1], "capi") == 0) {
        return capi(atol(argv[2]), argc > 3 && strcmp(argv[3], "read") == 0);
    }
    if (argc >= 6 && strcmp(argv[1], "fmu") == 0) {
        const char *opt = argc > 6 ? argv[6] : "";
        return fmu(atol(argv[2]), argv[3], argv[4], argv[5], strcmp(opt, "read") == 0,
                   strcmp(opt, "load") == 0);
    }
    fprintf(stderr, "usage: overhead capi N [read] | overhead fmu N LIB TOKEN RESOURCES [read]\n");
    return 2;
}
