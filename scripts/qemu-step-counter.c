/*
 * QEMU TCG plugin: exact guest instruction count of every call of one function.
 *
 * Counts the instructions executed from the function's entry (a translation block starting at
 * `entry`) until control comes back to the caller (a block starting at `ret`, the address after
 * a call; `ret=` may be given once per call site), including everything the function calls.
 * Writes one count per call, in call order, to `out`; with `prof=<path>`, also the instructions
 * executed inside the calls per translation block (`<pc> <instructions in the block> <count>`, for a profile);
 * with `only=<n>` as well, the profile of the n-th call alone (1 = the first).
 * Built and used by scripts/embedded-report.sh:
 *
 *   gcc -O2 -shared -fPIC -o step-counter.so scripts/qemu-step-counter.c
 *   qemu-system-arm ... -plugin ./step-counter.so,entry=0x1234,ret=0x5678,out=counts.txt
 *
 * With `op=<entry>/<ret>/<ret>…` (up to 16 times: the operations), each line also carries, per
 * operation in the order given, the calls made during that outer call, the instructions executed
 * inside them (entry to return address, callees included) and the most in one of those calls:
 * `<total> <calls> <insns> <most> …`.
 * Operations do not nest (an operation entered while another runs counts towards the first).
 *
 * Written against the QEMU plugin API version 1 (QEMU 6.x-8.1, e.g. Debian 12's QEMU 7.2).
 * Debian ships no plugin headers, so the few declarations needed are repeated here.
 */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define EXPORT __attribute__((visibility("default")))

typedef uint64_t qemu_plugin_id_t;
struct qemu_plugin_tb;
typedef struct qemu_info_t qemu_info_t;
enum qemu_plugin_cb_flags { QEMU_PLUGIN_CB_NO_REGS };
typedef void (*qemu_plugin_vcpu_udata_cb_t)(unsigned int vcpu_index, void *userdata);
typedef void (*qemu_plugin_vcpu_tb_trans_cb_t)(qemu_plugin_id_t id, struct qemu_plugin_tb *tb);
typedef void (*qemu_plugin_udata_cb_t)(qemu_plugin_id_t id, void *userdata);
void qemu_plugin_register_vcpu_tb_trans_cb(qemu_plugin_id_t id, qemu_plugin_vcpu_tb_trans_cb_t cb);
void qemu_plugin_register_vcpu_tb_exec_cb(struct qemu_plugin_tb *tb, qemu_plugin_vcpu_udata_cb_t cb,
                                          enum qemu_plugin_cb_flags flags, void *userdata);
void qemu_plugin_register_atexit_cb(qemu_plugin_id_t id, qemu_plugin_udata_cb_t cb, void *userdata);
size_t qemu_plugin_tb_n_insns(const struct qemu_plugin_tb *tb);
uint64_t qemu_plugin_tb_vaddr(const struct qemu_plugin_tb *tb);

EXPORT int qemu_plugin_version = 1;

struct block {
    uint64_t pc;
    uint64_t n;
    uint64_t inside; /* instructions executed in this block during counted calls */
    struct block *next;
};

#define MAX_RET 64
static struct block *blocks;

#define MAX_OPS 16
struct op {
    uint64_t entry, ret[MAX_RET];
    int n_ret;
    uint64_t calls, insns, cur, maxcall;
};
static struct op ops[MAX_OPS];
static int n_ops, active_op = -1;

static uint64_t entry, ret[MAX_RET];
static int n_ret;
static int counting;
static uint64_t current, calls, only;
static FILE *out, *prof;

static void on_exec(unsigned int vcpu, void *udata)
{
    const struct block *b = udata;
    (void)vcpu;
    if (counting && active_op >= 0) {
        struct op *o = &ops[active_op];
        for (int i = 0; i < o->n_ret; i++) {
            if (b->pc == o->ret[i]) {
                if (o->cur > o->maxcall) {
                    o->maxcall = o->cur;
                }
                active_op = -1;
                break;
            }
        }
    }
    if (counting) {
        for (int i = 0; i < n_ret; i++) {
            if (b->pc == ret[i]) {
                fprintf(out, "%" PRIu64, current);
                for (int k = 0; k < n_ops; k++) {
                    fprintf(out, " %" PRIu64 " %" PRIu64 " %" PRIu64, ops[k].calls, ops[k].insns,
                            ops[k].maxcall);
                    ops[k].calls = ops[k].insns = ops[k].maxcall = 0;
                }
                fprintf(out, "\n");
                active_op = -1;
                calls++;
                counting = 0;
                break;
            }
        }
    }
    if (b->pc == entry) {
        counting = 1;
        current = 0;
    }
    if (counting && active_op < 0) {
        for (int k = 0; k < n_ops; k++) {
            if (b->pc == ops[k].entry) {
                active_op = k;
                ops[k].calls++;
                ops[k].cur = 0;
                break;
            }
        }
    }
    if (counting) {
        current += b->n;
        if (active_op >= 0) {
            ops[active_op].insns += b->n;
            ops[active_op].cur += b->n;
        }
        if (!only || calls + 1 == only) {
            ((struct block *)udata)->inside += b->n;
        }
    }
}

static void on_translate(qemu_plugin_id_t id, struct qemu_plugin_tb *tb)
{
    struct block *b = malloc(sizeof *b);
    (void)id;
    if (!b) {
        abort();
    }
    b->pc = qemu_plugin_tb_vaddr(tb);
    b->n = qemu_plugin_tb_n_insns(tb);
    b->inside = 0;
    b->next = blocks;
    blocks = b;
    qemu_plugin_register_vcpu_tb_exec_cb(tb, on_exec, QEMU_PLUGIN_CB_NO_REGS, b);
}

static void at_exit(qemu_plugin_id_t id, void *udata)
{
    (void)id;
    (void)udata;
    if (out) {
        fflush(out);
    }
    if (prof) {
        for (const struct block *b = blocks; b; b = b->next) {
            if (b->inside) {
                fprintf(prof, "0x%" PRIx64 " %" PRIu64 " %" PRIu64 "\n", b->pc, b->n, b->inside);
            }
        }
        fclose(prof);
        prof = NULL;
    }
}

EXPORT int qemu_plugin_install(qemu_plugin_id_t id, const qemu_info_t *info, int argc, char **argv)
{
    const char *path = NULL;
    (void)info;
    for (int i = 0; i < argc; i++) {
        if (!strncmp(argv[i], "entry=", 6)) {
            entry = strtoull(argv[i] + 6, NULL, 0) & ~1ull;
        } else if (!strncmp(argv[i], "ret=", 4) && n_ret < MAX_RET) {
            ret[n_ret++] = strtoull(argv[i] + 4, NULL, 0) & ~1ull;
        } else if (!strncmp(argv[i], "op=", 3) && n_ops < MAX_OPS) {
            struct op *o = &ops[n_ops++];
            char *p = argv[i] + 3;
            o->entry = strtoull(p, &p, 0) & ~1ull;
            while (*p == '/' && o->n_ret < MAX_RET) {
                o->ret[o->n_ret++] = strtoull(p + 1, &p, 0) & ~1ull;
            }
            if (!o->entry || !o->n_ret) {
                fprintf(stderr, "step-counter: op=<entry>/<ret>[/<ret>…] expected, got %s\n", argv[i]);
                return 1;
            }
        } else if (!strncmp(argv[i], "only=", 5)) {
            only = strtoull(argv[i] + 5, NULL, 0);
        } else if (!strncmp(argv[i], "prof=", 5)) {
            if (!(prof = fopen(argv[i] + 5, "w"))) {
                return 1;
            }
        } else if (!strncmp(argv[i], "out=", 4)) {
            path = argv[i] + 4;
        } else {
            fprintf(stderr, "step-counter: unknown argument %s\n", argv[i]);
            return 1;
        }
    }
    if (!entry || !n_ret || !path || !(out = fopen(path, "w"))) {
        fprintf(stderr, "step-counter: need entry=, ret= and a writable out=\n");
        return 1;
    }
    qemu_plugin_register_vcpu_tb_trans_cb(id, on_translate);
    qemu_plugin_register_atexit_cb(id, at_exit, NULL);
    return 0;
}
