/* A co-simulation host with no Python in the process: loads FMUs through libcosim's C API
 * (libcosimc), steps the execution, writes chosen outputs to CSV and says what the process
 * had mapped (issue 28, item 4).
 *
 *     host CONFIG OUT.csv
 *
 * CONFIG is a text file, one directive a line ('#' starts a comment):
 *
 *     ssp PATH                  an SSP package (.ssp or a directory holding SystemStructure.ssd)
 *     step SECONDS              without ssp: the fixed communication step of a new execution
 *     slave NAME PATH           without ssp: an FMU instance NAME of the FMU at PATH
 *     connect FROM.out TO.in    without ssp: a Real output feeds a Real input
 *     real NAME.variable VALUE  a Real initial value
 *     output NAME.variable      a column of OUT.csv (after "time")
 *     stop SECONDS              the simulated time (required)
 *     every N                   a CSV row every N steps (default 1; 0: none, and no observer)
 *
 * On success it prints "key value" lines to stdout: steps, simulated_s, setup_cpu_s (loading,
 * wiring and the first step, in which libcosim initialises the FMUs), then for the steps
 * after it timed_s (their simulated time), cpu_s (CPU of all threads), thread_cpu_s (CPU of
 * the calling thread alone: the rest is libcosim's worker threads) and wall_s, CSV rows
 * included; threads (the process's threads after the steps, from /proc/self/status); libpython_mapped
 * (lines of /proc/self/maps naming libpython), python_symbol (whether Py_Initialize resolves
 * in the process) and fmu_binaries (the mapped FMU binaries, by file name).  Exit status 2 on
 * any error, with libcosim's message on stderr.
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "cosim_api.h"
#include "host_clock.h"

enum { MAX_ITEMS = 64, NAME_SIZE = 256, PATH_SIZE = 4096, LINE_SIZE = 8192 };

/* A variable named "slave.variable". */
typedef struct {
    char slave[NAME_SIZE];
    char variable[NAME_SIZE];
} VariableName;

/* A variable found in the execution. */
typedef struct {
    cosim_slave_index slave;
    cosim_value_reference vr;
} VariableRef;

typedef struct {
    char ssp[PATH_SIZE];
    double step_s;
    double stop_s;
    long every;
    int n_slaves;
    char slave_names[MAX_ITEMS][NAME_SIZE];
    char slave_paths[MAX_ITEMS][PATH_SIZE];
    int n_connections;
    VariableName connection_from[MAX_ITEMS];
    VariableName connection_to[MAX_ITEMS];
    int n_initial;
    VariableName initial[MAX_ITEMS];
    double initial_values[MAX_ITEMS];
    int n_outputs;
    VariableName outputs[MAX_ITEMS];
} Config;

static void fail(const char *what, const char *detail)
{
    fprintf(stderr, "host: %s%s%s\n", what, detail ? ": " : "", detail ? detail : "");
    exit(2);
}

static void fail_cosim(const char *what)
{
    fail(what, cosim_last_error_message());
}

static void copy_text(char *to, size_t size, const char *from, const char *what)
{
    if (strlen(from) >= size)
        fail("too long", what);
    strcpy(to, from);
}

static void split_name(const char *text, VariableName *name)
{
    const char *dot = strchr(text, '.');
    if (!dot || dot == text || !dot[1])
        fail("a variable must be written SLAVE.VARIABLE", text);
    size_t n = (size_t)(dot - text);
    if (n >= NAME_SIZE)
        fail("slave name too long", text);
    memcpy(name->slave, text, n);
    name->slave[n] = '\0';
    copy_text(name->variable, NAME_SIZE, dot + 1, text);
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

static int next_index(int *count, const char *directive)
{
    if (*count >= MAX_ITEMS)
        fail("too many lines of", directive);
    return (*count)++;
}

static void parse_line(Config *c, char *line)
{
    char *hash = strchr(line, '#');
    if (hash)
        *hash = '\0';
    char *key = strtok(line, " \t\r\n");
    if (!key)
        return;
    char *a = strtok(NULL, " \t\r\n");
    char *b = strtok(NULL, " \t\r\n");
    if (!a)
        fail("missing argument of", key);
    if (!strcmp(key, "ssp")) {
        copy_text(c->ssp, PATH_SIZE, a, "ssp");
    } else if (!strcmp(key, "step")) {
        c->step_s = parse_number(a, key);
    } else if (!strcmp(key, "stop")) {
        c->stop_s = parse_number(a, key);
    } else if (!strcmp(key, "every")) {
        c->every = (long)parse_number(a, key);
    } else if (!strcmp(key, "slave")) {
        int i = next_index(&c->n_slaves, key);
        copy_text(c->slave_names[i], NAME_SIZE, a, key);
        copy_text(c->slave_paths[i], PATH_SIZE, b ? b : "", key);
        if (!b)
            fail("slave needs a name and an FMU path", a);
    } else if (!strcmp(key, "connect")) {
        int i = next_index(&c->n_connections, key);
        split_name(a, &c->connection_from[i]);
        split_name(b ? b : "", &c->connection_to[i]);
    } else if (!strcmp(key, "real")) {
        int i = next_index(&c->n_initial, key);
        split_name(a, &c->initial[i]);
        c->initial_values[i] = parse_number(b, key);
    } else if (!strcmp(key, "output")) {
        split_name(a, &c->outputs[next_index(&c->n_outputs, key)]);
    } else {
        fail("unknown directive", key);
    }
}

static void read_config(const char *path, Config *c)
{
    FILE *f = fopen(path, "r");
    if (!f)
        fail("cannot open the configuration", path);
    char line[LINE_SIZE];
    memset(c, 0, sizeof *c);
    c->every = 1;
    while (fgets(line, sizeof line, f))
        parse_line(c, line);
    fclose(f);
    if (!(c->stop_s > 0.0))
        fail("the configuration needs 'stop SECONDS' > 0", path);
    if (!c->ssp[0] && (c->n_slaves == 0 || !(c->step_s > 0.0)))
        fail("without 'ssp' the configuration needs 'step SECONDS' > 0 and at least one 'slave'", path);
}

static cosim_time_point nanoseconds(double seconds)
{
    return (cosim_time_point)(seconds * 1e9 + (seconds >= 0.0 ? 0.5 : -0.5));
}

static cosim_execution *create_execution(const Config *c)
{
    if (c->ssp[0]) {
        cosim_execution *e = cosim_ssp_execution_create(c->ssp, false, 0);
        if (!e)
            fail_cosim("cannot load the SSP package");
        return e;
    }
    cosim_execution *e = cosim_execution_create(0, nanoseconds(c->step_s));
    if (!e)
        fail_cosim("cannot create the execution");
    for (int i = 0; i < c->n_slaves; i++) {
        cosim_slave *slave = cosim_local_slave_create(c->slave_paths[i], c->slave_names[i]);
        if (!slave || cosim_execution_add_slave(e, slave) < 0)
            fail_cosim(c->slave_paths[i]);
    }
    return e;
}

static cosim_slave_index find_slave(cosim_execution *e, const char *name)
{
    cosim_slave_info infos[MAX_ITEMS];
    size_t n = cosim_execution_get_num_slaves(e);
    if (n > MAX_ITEMS || cosim_execution_get_slave_infos(e, infos, n) < 0)
        fail_cosim("cannot list the slaves");
    for (size_t i = 0; i < n; i++)
        if (!strcmp(infos[i].name, name))
            return infos[i].index;
    fail("no slave named", name);
    return -1;
}

static VariableRef find_variable(cosim_execution *e, const VariableName *name)
{
    VariableRef ref = {find_slave(e, name->slave), 0};
    int n = cosim_slave_get_num_variables(e, ref.slave);
    if (n < 0)
        fail_cosim(name->slave);
    cosim_variable_description *variables = calloc((size_t)n + 1, sizeof *variables);
    if (!variables || cosim_slave_get_variables(e, ref.slave, variables, (size_t)n) < 0)
        fail_cosim(name->slave);
    int found = 0;
    for (int i = 0; i < n && !found; i++)
        if (!strcmp(variables[i].name, name->variable) && variables[i].type == COSIM_REAL) {
            ref.vr = variables[i].reference;
            found = 1;
        }
    free(variables);
    if (!found)
        fail("no Real variable of this name in its slave", name->variable);
    return ref;
}

static void wire(cosim_execution *e, const Config *c)
{
    for (int i = 0; i < c->n_connections; i++) {
        VariableRef from = find_variable(e, &c->connection_from[i]);
        VariableRef to = find_variable(e, &c->connection_to[i]);
        if (cosim_execution_connect_real_variables(e, from.slave, from.vr, to.slave, to.vr) < 0)
            fail_cosim(c->connection_to[i].variable);
    }
    for (int i = 0; i < c->n_initial; i++) {
        VariableRef ref = find_variable(e, &c->initial[i]);
        if (cosim_execution_set_real_initial_value(e, ref.slave, ref.vr, c->initial_values[i]) < 0)
            fail_cosim(c->initial[i].variable);
    }
}

static cosim_time_point current_time(cosim_execution *e)
{
    cosim_execution_status status;
    if (cosim_execution_get_status(e, &status) < 0)
        fail_cosim("cannot read the execution's status");
    return status.current_time;
}

static void write_row(FILE *csv, cosim_observer *observer, const VariableRef *refs, int n, cosim_time_point now)
{
    fprintf(csv, "%.9f", 1e-9 * (double)now);
    for (int i = 0; i < n; i++) {
        double value;
        if (cosim_observer_slave_get_real(observer, refs[i].slave, &refs[i].vr, 1, &value) < 0)
            fail_cosim("cannot read an output");
        fprintf(csv, ",%.17g", value);
    }
    fputc('\n', csv);
}

static void step_once(cosim_execution *e, FILE *csv, cosim_observer *observer, const VariableRef *refs,
                      const Config *c, long *steps, cosim_time_point *now, int rows)
{
    if (cosim_execution_step(e, 1) < 0)
        fail_cosim("a step failed");
    ++*steps;
    *now = current_time(e);
    if (rows && *steps % c->every == 0)
        write_row(csv, observer, refs, c->n_outputs, *now);
}

/* Prints what the process has mapped: libpython (must be nothing) and the FMU binaries. */
static void report_mappings(void)
{
    FILE *maps = fopen("/proc/self/maps", "r");
    if (!maps)
        fail("cannot read /proc/self/maps", strerror(errno));
    char line[LINE_SIZE], seen[LINE_SIZE] = "";
    long libpython = 0;
    while (fgets(line, sizeof line, maps)) {
        line[strcspn(line, "\n")] = '\0';
        if (strstr(line, "libpython"))
            libpython++;
        const char *binaries = strstr(line, "/binaries/");
        const char *file = binaries ? strrchr(binaries, '/') + 1 : NULL;
        if (file && !strstr(seen, file) && strlen(seen) + strlen(file) + 2 < sizeof seen) {
            strcat(seen, seen[0] ? "," : "");
            strcat(seen, file);
        }
    }
    fclose(maps);
    printf("libpython_mapped %ld\n", libpython);
    printf("python_symbol %d\n", dlsym(RTLD_DEFAULT, "Py_Initialize") != NULL);
    printf("fmu_binaries %s\n", seen[0] ? seen : "-");
}

int main(int argc, char **argv)
{
    if (argc != 3) {
        fprintf(stderr, "usage: %s CONFIG OUT.csv\n", argv[0]);
        return 2;
    }
    static Config config;
    read_config(argv[1], &config);
    cosim_log_set_output_level(COSIM_LOG_ERROR);
    double setup_cpu = clock_seconds(CLOCK_PROCESS_CPUTIME_ID);
    cosim_execution *execution = create_execution(&config);
    wire(execution, &config);
    /* An observer reads every variable of every slave after each step: only when rows are wanted. */
    const int rows = config.every > 0 && config.n_outputs > 0;
    cosim_observer *observer = rows ? cosim_last_value_observer_create() : NULL;
    if (rows && (!observer || cosim_execution_add_observer(execution, observer) < 0))
        fail_cosim("cannot add an observer");
    VariableRef refs[MAX_ITEMS];
    for (int i = 0; i < config.n_outputs; i++)
        refs[i] = find_variable(execution, &config.outputs[i]);

    FILE *csv = fopen(argv[2], "w");
    if (!csv)
        fail("cannot write", argv[2]);
    fputs("time", csv);
    for (int i = 0; i < config.n_outputs; i++)
        fprintf(csv, ",%s.%s", config.outputs[i].slave, config.outputs[i].variable);
    fputc('\n', csv);

    const cosim_time_point stop = nanoseconds(config.stop_s);
    long steps = 0;
    cosim_time_point now = current_time(execution);
    /* libcosim initialises the FMUs in the first step: that step counts as set-up. */
    if (now < stop)
        step_once(execution, csv, observer, refs, &config, &steps, &now, rows);
    setup_cpu = clock_seconds(CLOCK_PROCESS_CPUTIME_ID) - setup_cpu;
    const cosim_time_point timed_from = now;
    double cpu = clock_seconds(CLOCK_PROCESS_CPUTIME_ID), own = clock_seconds(CLOCK_THREAD_CPUTIME_ID),
           wall = clock_seconds(CLOCK_MONOTONIC);
    while (now < stop)
        step_once(execution, csv, observer, refs, &config, &steps, &now, rows);
    cpu = clock_seconds(CLOCK_PROCESS_CPUTIME_ID) - cpu;
    own = clock_seconds(CLOCK_THREAD_CPUTIME_ID) - own;
    wall = clock_seconds(CLOCK_MONOTONIC) - wall;
    if (fclose(csv) != 0)
        fail("cannot write", argv[2]);

    printf("steps %ld\nsimulated_s %.9f\ntimed_s %.9f\nsetup_cpu_s %.6f\ncpu_s %.6f\nthread_cpu_s %.6f\nwall_s %.6f\n"
           "threads %ld\n", steps, 1e-9 * (double)now, 1e-9 * (double)(now - timed_from), setup_cpu, cpu, own, wall,
           thread_count());
    report_mappings();
    cosim_execution_destroy(execution);
    if (observer)
        cosim_observer_destroy(observer);
    return 0;
}
