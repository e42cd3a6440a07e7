/* A plain FMI 2.0 co-simulation host in C: no co-simulation library, no Python.  It loads
 * each FMU's binary with dlopen, calls its fmi2 functions itself and steps the FMUs as a
 * Jacobi master (every FMU steps from t = k h, then every connection copies its output to
 * its input), on the calling thread.  The connections move in one fmi2GetReal per FMU that
 * feeds any and one fmi2SetReal per FMU fed (as libcosim gets and sets per slave).  What it
 * costs is the FMUs' own cost plus those calls: the floor any C host starts from (issue 28,
 * item 6).
 *
 *     fmi2_host CONFIG
 *
 * CONFIG, one directive a line ('#' starts a comment); the caller resolves names to value
 * references (tests/native_host/c_hosts.py writes it from FMU files or an SSP package):
 *
 *     step SECONDS                                    the communication step (required)
 *     stop SECONDS                                    the simulated time (required)
 *     slave NAME BINARY MODEL_IDENTIFIER GUID URI     an instance of the FMU whose unpacked
 *                                                     binary is BINARY (URI: its resources)
 *     connect FROM VR TO VR                           Real output VR of slave FROM feeds
 *                                                     Real input VR of slave TO
 *     real NAME VR VALUE                              a Real set in Initialization Mode
 *     output NAME VR                                  a Real read after every step
 *     profile 1                                       time each FMU's doSteps and the
 *                                                     transfers apart (the thread's CPU clock)
 *
 * After exiting initialisation the outputs are passed to the inputs before the first step
 * (as libcosim and Ecos do).  It prints "key value" lines: steps, simulated_s, setup_cpu_s
 * (loading, instantiating, initialising and the first step), timed_s, cpu_s (process CPU of
 * the later steps), wall_s, threads; with profile, dostep_s.NAME per slave and transfer_s
 * (CPU of the later steps' doSteps and connections, each less the clock's own cost per
 * reading, clock_s: a CPU clock is a system call, a wall clock would count the time other
 * processes took the CPU); then value.NAME.VR, the last
 * value of each output, %.17g.  Exit status 2 on any error, with the reason on stderr.
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fmi2Functions.h"
#include "host_clock.h"

enum { MAX_SLAVES = 64, MAX_LINKS = 256, TEXT_SIZE = 4096, LINE_SIZE = 16384 };

typedef struct {
    char name[TEXT_SIZE];
    char binary[TEXT_SIZE];
    char identifier[TEXT_SIZE];
    char guid[TEXT_SIZE];
    char uri[TEXT_SIZE];
    void *library;
    fmi2Component instance;
    fmi2InstantiateTYPE *instantiate;
    fmi2SetupExperimentTYPE *setup_experiment;
    fmi2EnterInitializationModeTYPE *enter_initialization;
    fmi2ExitInitializationModeTYPE *exit_initialization;
    fmi2DoStepTYPE *do_step;
    fmi2GetRealTYPE *get_real;
    fmi2SetRealTYPE *set_real;
    fmi2TerminateTYPE *terminate;
    fmi2FreeInstanceTYPE *free_instance;
    double dostep_s;
    /* the outputs it feeds (each once) and the inputs it is fed, with their values */
    int n_gets, n_sets;
    fmi2ValueReference get_vrs[MAX_LINKS], set_vrs[MAX_LINKS];
    double got[MAX_LINKS], put[MAX_LINKS];
} Slave;

/* A Real variable of a slave, by index. */
typedef struct {
    int slave;
    fmi2ValueReference vr;
} Ref;

typedef struct {
    double step_s;
    double stop_s;
    int profile;
    int n_slaves;
    Slave slaves[MAX_SLAVES];
    int n_links;
    Ref from[MAX_LINKS];
    Ref to[MAX_LINKS];
    int got_at[MAX_LINKS], put_at[MAX_LINKS];   /* each connection's place in got[] and put[] */
    int n_initial;
    Ref initial[MAX_LINKS];
    double initial_values[MAX_LINKS];
    int n_outputs;
    Ref outputs[MAX_LINKS];
    double values[MAX_LINKS];
} Host;

static void fail(const char *what, const char *detail)
{
    fprintf(stderr, "fmi2_host: %s%s%s\n", what, detail ? ": " : "", detail ? detail : "");
    exit(2);
}

static void logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status, fmi2String category,
                   fmi2String message, ...)
{
    (void)env;
    (void)category;
    if (status < fmi2Warning)
        return;
    va_list args;
    va_start(args, message);
    fprintf(stderr, "fmi2_host: %s: ", instance ? instance : "?");
    vfprintf(stderr, message, args);
    fputc('\n', stderr);
    va_end(args);
}

static const fmi2CallbackFunctions CALLBACKS = {logger, calloc, free, NULL, NULL};

static void copy_text(char *to, const char *from, const char *what)
{
    if (!from)
        fail("missing argument of", what);
    if (strlen(from) >= TEXT_SIZE)
        fail("too long", what);
    strcpy(to, from);
}

static double parse_number(const char *text, const char *directive)
{
    char *end;
    errno = 0;
    double value = strtod(text ? text : "", &end);
    if (!text || end == text || *end || errno)
        fail("not a number after", directive);
    return value;
}

static int slave_index(const Host *h, const char *name)
{
    for (int i = 0; i < h->n_slaves; i++)
        if (name && !strcmp(h->slaves[i].name, name))
            return i;
    fail("no slave named", name ? name : "(missing)");
    return -1;
}

static Ref parse_ref(const Host *h, const char *slave, const char *vr, const char *directive)
{
    Ref r = {slave_index(h, slave), (fmi2ValueReference)parse_number(vr, directive)};
    return r;
}

static void *symbol(Slave *s, const char *name)
{
    void *f = dlsym(s->library, name);
    if (!f)
        fail("the FMU's binary lacks", name);
    return f;
}

static void load(Slave *s)
{
    s->library = dlopen(s->binary, RTLD_NOW | RTLD_LOCAL);
    if (!s->library)
        fail("cannot load", dlerror());
    s->instantiate = (fmi2InstantiateTYPE *)symbol(s, "fmi2Instantiate");
    s->setup_experiment = (fmi2SetupExperimentTYPE *)symbol(s, "fmi2SetupExperiment");
    s->enter_initialization = (fmi2EnterInitializationModeTYPE *)symbol(s, "fmi2EnterInitializationMode");
    s->exit_initialization = (fmi2ExitInitializationModeTYPE *)symbol(s, "fmi2ExitInitializationMode");
    s->do_step = (fmi2DoStepTYPE *)symbol(s, "fmi2DoStep");
    s->get_real = (fmi2GetRealTYPE *)symbol(s, "fmi2GetReal");
    s->set_real = (fmi2SetRealTYPE *)symbol(s, "fmi2SetReal");
    s->terminate = (fmi2TerminateTYPE *)symbol(s, "fmi2Terminate");
    s->free_instance = (fmi2FreeInstanceTYPE *)symbol(s, "fmi2FreeInstance");
}

static void parse_line(Host *h, char *line)
{
    char *hash = strchr(line, '#');
    if (hash)
        *hash = '\0';
    char *key = strtok(line, " \t\r\n");
    if (!key)
        return;
    char *a[5];
    for (int i = 0; i < 5; i++)
        a[i] = strtok(NULL, " \t\r\n");
    if (!strcmp(key, "step")) {
        h->step_s = parse_number(a[0], key);
    } else if (!strcmp(key, "stop")) {
        h->stop_s = parse_number(a[0], key);
    } else if (!strcmp(key, "profile")) {
        h->profile = (int)parse_number(a[0], key);
    } else if (!strcmp(key, "slave")) {
        if (h->n_slaves >= MAX_SLAVES)
            fail("too many lines of", key);
        Slave *s = &h->slaves[h->n_slaves++];
        copy_text(s->name, a[0], key);
        copy_text(s->binary, a[1], key);
        copy_text(s->identifier, a[2], key);
        copy_text(s->guid, a[3], key);
        copy_text(s->uri, a[4], key);
    } else if (!strcmp(key, "connect")) {
        if (h->n_links >= MAX_LINKS)
            fail("too many lines of", key);
        h->from[h->n_links] = parse_ref(h, a[0], a[1], key);
        h->to[h->n_links++] = parse_ref(h, a[2], a[3], key);
    } else if (!strcmp(key, "real")) {
        if (h->n_initial >= MAX_LINKS)
            fail("too many lines of", key);
        h->initial[h->n_initial] = parse_ref(h, a[0], a[1], key);
        h->initial_values[h->n_initial++] = parse_number(a[2], key);
    } else if (!strcmp(key, "output")) {
        if (h->n_outputs >= MAX_LINKS)
            fail("too many lines of", key);
        h->outputs[h->n_outputs++] = parse_ref(h, a[0], a[1], key);
    } else {
        fail("unknown directive", key);
    }
}

static void read_config(const char *path, Host *h)
{
    FILE *f = fopen(path, "r");
    if (!f)
        fail("cannot open the configuration", path);
    char line[LINE_SIZE];
    while (fgets(line, sizeof line, f))
        parse_line(h, line);
    fclose(f);
    if (!(h->step_s > 0.0) || !(h->stop_s > 0.0) || h->n_slaves == 0)
        fail("the configuration needs 'step' > 0, 'stop' > 0 and at least one 'slave'", path);
}

static void check(fmi2Status status, const Slave *s, const char *call)
{
    if (status > fmi2Warning) {
        char text[2 * TEXT_SIZE];
        snprintf(text, sizeof text, "%s of %s returned status %d", call, s->name, (int)status);
        fail("a call failed", text);
    }
}

static void initialise(Host *h)
{
    for (int i = 0; i < h->n_slaves; i++) {
        Slave *s = &h->slaves[i];
        load(s);
        s->instance = s->instantiate(s->name, fmi2CoSimulation, s->guid, s->uri, &CALLBACKS, fmi2False, fmi2False);
        if (!s->instance)
            fail("fmi2Instantiate failed for", s->name);
        check(s->setup_experiment(s->instance, fmi2False, 0.0, 0.0, fmi2False, 0.0), s, "fmi2SetupExperiment");
        check(s->enter_initialization(s->instance), s, "fmi2EnterInitializationMode");
        for (int k = 0; k < h->n_initial; k++)
            if (h->initial[k].slave == i)
                check(s->set_real(s->instance, &h->initial[k].vr, 1, &h->initial_values[k]), s, "fmi2SetReal");
        check(s->exit_initialization(s->instance), s, "fmi2ExitInitializationMode");
    }
}

/* Each connection's places in its source's got[] (an output feeding several inputs is got
 * once) and its target's put[] (an input fed twice is refused). */
static void plan_transfers(Host *h)
{
    for (int i = 0; i < h->n_links; i++) {
        Slave *from = &h->slaves[h->from[i].slave], *to = &h->slaves[h->to[i].slave];
        int k = 0;
        while (k < from->n_gets && from->get_vrs[k] != h->from[i].vr)
            k++;
        if (k == from->n_gets)
            from->get_vrs[from->n_gets++] = h->from[i].vr;
        h->got_at[i] = k;
        for (int j = 0; j < to->n_sets; j++)
            if (to->set_vrs[j] == h->to[i].vr)
                fail("an input is fed by two connections, of", to->name);
        h->put_at[i] = to->n_sets;
        to->set_vrs[to->n_sets++] = h->to[i].vr;
    }
}

static void transfer(Host *h)
{
    for (int i = 0; i < h->n_slaves; i++) {
        Slave *s = &h->slaves[i];
        if (s->n_gets)
            check(s->get_real(s->instance, s->get_vrs, (size_t)s->n_gets, s->got), s, "fmi2GetReal");
    }
    for (int i = 0; i < h->n_links; i++)
        h->slaves[h->to[i].slave].put[h->put_at[i]] = h->slaves[h->from[i].slave].got[h->got_at[i]];
    for (int i = 0; i < h->n_slaves; i++) {
        Slave *s = &h->slaves[i];
        if (s->n_sets)
            check(s->set_real(s->instance, s->set_vrs, (size_t)s->n_sets, s->put), s, "fmi2SetReal");
    }
}

/* The profile's clock: the calling thread's CPU. */
static double profile_clock(void)
{
    return clock_seconds(CLOCK_THREAD_CPUTIME_ID);
}

/* What one interval of the profile's clock costs with nothing in it (the least of many). */
static double clock_cost(void)
{
    double least = 1.0;
    for (int i = 0; i < 10000; i++) {
        double a = profile_clock(), b = profile_clock();
        if (b - a < least)
            least = b - a;
    }
    return least;
}

static void step(Host *h, long k, double *transfer_s)
{
    const double t = (double)k * h->step_s;
    for (int i = 0; i < h->n_slaves; i++) {
        Slave *s = &h->slaves[i];
        double w = h->profile ? profile_clock() : 0.0;
        check(s->do_step(s->instance, t, h->step_s, fmi2True), s, "fmi2DoStep");
        if (h->profile)
            s->dostep_s += profile_clock() - w;
    }
    double w = h->profile ? profile_clock() : 0.0;
    transfer(h);
    for (int i = 0; i < h->n_outputs; i++) {
        Slave *s = &h->slaves[h->outputs[i].slave];
        check(s->get_real(s->instance, &h->outputs[i].vr, 1, &h->values[i]), s, "fmi2GetReal");
    }
    if (h->profile)
        *transfer_s += profile_clock() - w;
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: %s CONFIG\n", argv[0]);
        return 2;
    }
    static Host host;
    read_config(argv[1], &host);
    plan_transfers(&host);
    const long steps = (long)(host.stop_s / host.step_s + 0.5);
    double setup_cpu = clock_seconds(CLOCK_PROCESS_CPUTIME_ID), transfer_s = 0.0;
    initialise(&host);
    transfer(&host);
    step(&host, 0, &transfer_s);
    setup_cpu = clock_seconds(CLOCK_PROCESS_CPUTIME_ID) - setup_cpu;
    for (int i = 0; i < host.n_slaves; i++)
        host.slaves[i].dostep_s = 0.0;
    transfer_s = 0.0;
    double cpu = clock_seconds(CLOCK_PROCESS_CPUTIME_ID), wall = clock_seconds(CLOCK_MONOTONIC);
    for (long k = 1; k < steps; k++)
        step(&host, k, &transfer_s);
    cpu = clock_seconds(CLOCK_PROCESS_CPUTIME_ID) - cpu;
    wall = clock_seconds(CLOCK_MONOTONIC) - wall;
    printf("steps %ld\nsimulated_s %.9f\ntimed_s %.9f\nsetup_cpu_s %.6f\ncpu_s %.6f\nwall_s %.6f\nthreads %ld\n",
           steps, (double)steps * host.step_s, (double)(steps - 1) * host.step_s, setup_cpu, cpu, wall,
           thread_count());
    if (host.profile) {
        const double cost = clock_cost(), readings = (double)(steps - 1);
        for (int i = 0; i < host.n_slaves; i++)
            printf("dostep_s.%s %.6f\n", host.slaves[i].name, host.slaves[i].dostep_s - cost * readings);
        printf("transfer_s %.6f\nclock_s %.9f\n", transfer_s - cost * readings, cost);
    }
    for (int i = 0; i < host.n_outputs; i++)
        printf("value.%s.%u %.17g\n", host.slaves[host.outputs[i].slave].name, (unsigned)host.outputs[i].vr,
               host.values[i]);
    for (int i = 0; i < host.n_slaves; i++) {
        Slave *s = &host.slaves[i];
        check(s->terminate(s->instance), s, "fmi2Terminate");
        s->free_instance(s->instance);
    }
    return 0;
}
