/*
 * parcosim's FMI 2.0 co-simulation export wrapper.
 *
 * The shared library binaries/linux64/<modelIdentifier>.so of every parcosim FMU.  It
 * embeds the host's Python (libpython3.11: the importer must have it loaded, as for
 * pythonfmu's wrapper) and drives the FMU's pythonfmu slave class, read from
 * resources/slavemodule.txt, with pythonfmu's calling protocol (Fmi2Slave methods
 * set_real, do_step, _get_fmu_state ...).  Written for parcosim (issue 13); it replaces
 * pythonfmu 0.7's C++ wrapper, whose faults it avoids:
 *
 *  - the importer's logger gets each message as a printf format with every '%' doubled
 *    (no conversion, no argument): printf-style loggers and loggers that print the
 *    format as it is (fmpy) show the message; a message is never a format that reads
 *    arguments;
 *  - an instance name or a message that is not UTF-8 is decoded with "replace";
 *  - the resource URI (file:///, file:/, file://localhost/) is fully %XX-decoded; any
 *    other scheme refuses the instance with a logged reason;
 *  - a Python exception in a callback, KeyboardInterrupt and parcosim's FmiError included,
 *    is fmi2Error with its message logged; the instance stays valid and can be freed.
 *    A do_step returning False is fmi2Discard.  fmi2Fatal is never returned: the only
 *    unrecoverable failure (Python cannot be initialised) makes fmi2Instantiate NULL;
 *  - value references are checked against the slave's variables and their types, strings
 *    set must be UTF-8, NULL arrays are refused: fmi2Error naming the variable;
 *  - the slave's code is the FMU's own: a parcosim FMU's bundle (resources/<package>, the
 *    package named by resources/parcosim_build.json, fmus/export/bundle.py) is loaded under its
 *    private name without touching sys.path; an instantiation whose GUID (fmuGUID) or binary
 *    (its modelIdentifier: this library's file name) is not the one the resources' identity
 *    names is refused (resources of another FMU).  No Python reference is kept past
 *    fmi2FreeInstance;
 *  - an FMU state pointer is set, serialised or freed only by the instance that issued it
 *    (fmi2GetFMUstate or fmi2DeSerializeFMUstate); a parcosim slave reads serialised bytes
 *    against its own instance (deserialize_fmu_state: data, never code; docs/state.md);
 *  - Python is initialised only if the host has not done it; every call takes the GIL with
 *    PyGILState_Ensure and then one process-wide lock that every parcosim wrapper loaded
 *    (one per FMU type) shares, so that no two FMUs import or run Python at once from two
 *    threads; nothing is finalised at exit or unload.
 *
 * Build (fmus/export/wrapper/__init__.py does it once per machine):
 *   cc -O2 -fPIC -shared -fvisibility=hidden -I<python include> parcosim_fmi2.c -o w.so
 * Python's symbols are left to the host process (not linked), as pythonfmu does.
 */
#define _GNU_SOURCE   /* dladdr */
#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include <dlfcn.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PARCOSIM_FMI2_WRAPPER_VERSION "parcosim-fmi2-wrapper 1.1"
#define EXPORT __attribute__((visibility("default")))

/* ---- FMI 2.0 types (as the standard's fmi2TypesPlatform.h / fmi2FunctionTypes.h define them) ---- */
typedef void *fmi2Component;
typedef void *fmi2ComponentEnvironment;
typedef void *fmi2FMUstate;
typedef unsigned int fmi2ValueReference;
typedef double fmi2Real;
typedef int fmi2Integer;
typedef int fmi2Boolean;
typedef char fmi2Char;
typedef const fmi2Char *fmi2String;
typedef char fmi2Byte;
#define fmi2True 1
#define fmi2False 0

typedef enum { fmi2OK, fmi2Warning, fmi2Discard, fmi2Error, fmi2Fatal, fmi2Pending } fmi2Status;
typedef enum { fmi2ModelExchange, fmi2CoSimulation } fmi2Type;
typedef enum { fmi2DoStepStatus, fmi2PendingStatus, fmi2LastSuccessfulTime, fmi2Terminated } fmi2StatusKind;

typedef void (*fmi2CallbackLogger)(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String, fmi2String, ...);
typedef void *(*fmi2CallbackAllocateMemory)(size_t, size_t);
typedef void (*fmi2CallbackFreeMemory)(void *);
typedef void (*fmi2StepFinished)(fmi2ComponentEnvironment, fmi2Status);

typedef struct {
    const fmi2CallbackLogger logger;
    const fmi2CallbackAllocateMemory allocateMemory;
    const fmi2CallbackFreeMemory freeMemory;
    const fmi2StepFinished stepFinished;
    const fmi2ComponentEnvironment componentEnvironment;
} fmi2CallbackFunctions;

/* ---- one FMU instance ---- */
enum { KIND_NONE = 0, KIND_REAL = 'R', KIND_INTEGER = 'I', KIND_BOOLEAN = 'B', KIND_STRING = 'S' };

typedef struct {
    char *name;                      /* the instance name as given (bytes), for the logger */
    fmi2CallbackLogger logger;       /* may be NULL */
    fmi2ComponentEnvironment env;
    int logging_on;
    size_t n_categories;
    char **categories;               /* fmi2SetDebugLogging's categories (none: all) */
    PyObject *kwargs;                /* the slave class's keyword arguments (fmi2Reset re-creates it) */
    PyObject *cls;                   /* the Fmi2Slave subclass */
    PyObject *slave;                 /* its instance */
    PyObject *log_queue;             /* slave.log_queue (a list of pythonfmu LogMsg) */
    char *kinds;                     /* value reference -> KIND_* */
    size_t n_kinds;
    PyObject *strings;               /* the bytes fmi2GetString returned last (kept alive for the caller) */
    double time;                     /* the current communication point */
    double last_successful_time;
} Instance;

#define STATE_MAGIC 0x70636673u      /* "pcfs": a live FMU state of this wrapper */
typedef struct {
    unsigned int magic;
    const Instance *owner;           /* the instance that issued it: no other may set it */
    PyObject *state;
    PyObject *serialized;            /* bytes of the state, made by fmi2SerializedFMUstateSize */
} State;

/* Interned method and attribute names, created once per process under the GIL. */
static PyObject *s_get_real, *s_get_integer, *s_get_boolean, *s_get_string;
static PyObject *s_set_real, *s_set_integer, *s_set_boolean, *s_set_string;
static PyObject *s_do_step, *s_setup_experiment, *s_enter_init, *s_exit_init, *s_terminate;
static PyObject *s_get_fmu_state, *s_set_fmu_state, *s_to_bytes, *s_from_bytes, *s_deserialize;
static PyObject *s_msg, *s_category, *s_status, *s_vars, *s_name, *s_log_queue;
static PyObject *c_fmi2slave, *c_real, *c_integer, *c_boolean, *c_string;
static pthread_mutex_t init_lock = PTHREAD_MUTEX_INITIALIZER;
static PyObject *loader_slave_class;  /* slave_class of LOADER_SOURCE */
static pthread_mutex_t *python_lock;  /* the process-wide lock (shared_lock) */

EXPORT const char *parcosimFmi2WrapperVersion(void) { return PARCOSIM_FMI2_WRAPPER_VERSION; }

/* ---- logging ---- */

static int wants_category(const Instance *in, const char *category)
{
    size_t i;
    if (!in->logging_on) return 0;
    if (in->n_categories == 0) return 1;
    for (i = 0; i < in->n_categories; i++)
        if (strcmp(in->categories[i], category) == 0) return 1;
    return 0;
}

/* The message as a printf format that prints it: every '%' doubled (a malloc'd string).
 * FMI 2.0 makes the logger's message a printf format, but many loggers (fmpy's, through
 * ctypes) print it as it is: an escaped format is right for both, and a message can never
 * be a format with conversions (pythonfmu's format-string crash). */
static char *as_format(const char *message)
{
    size_t n = 0;
    const char *p;
    char *out, *o;
    for (p = message; *p; p++) n += *p == '%' ? 2 : 1;
    out = o = malloc(n + 1);
    if (out == NULL) return NULL;
    for (p = message; *p; p++) {
        *o++ = *p;
        if (*p == '%') *o++ = '%';
    }
    *o = '\0';
    return out;
}

/* Forward one message: errors always, the rest if logging is on for its category. */
static void emit(const Instance *in, fmi2Status status, const char *category, const char *message)
{
    char *format;
    if (in == NULL || in->logger == NULL) return;
    if (status < fmi2Error && !wants_category(in, category)) return;
    format = as_format(message);
    if (format != NULL) in->logger(in->env, in->name, status, category, format);
    else in->logger(in->env, in->name, status, category, "%s", message);
    free(format);
}

static char *vformat(const char *fmt, va_list ap)
{
    va_list copy;
    int n;
    char *text;
    va_copy(copy, ap);
    n = vsnprintf(NULL, 0, fmt, copy);
    va_end(copy);
    if (n < 0) return NULL;
    text = malloc((size_t)n + 1);
    if (text != NULL) vsnprintf(text, (size_t)n + 1, fmt, ap);
    return text;
}

/* Log a message of the wrapper; fmt is always a constant of this file. */
static void logf_(const Instance *in, fmi2Status status, const char *fmt, ...)
{
    va_list ap;
    char *text;
    if (in == NULL || in->logger == NULL) return;
    va_start(ap, fmt);
    text = vformat(fmt, ap);
    va_end(ap);
    emit(in, status, status >= fmi2Error ? "logStatusError" : "logAll", text ? text : "(out of memory)");
    free(text);
}

/* A log message for a refused instantiation, with its own logger and name. */
static void log_instantiate(const fmi2CallbackFunctions *f, fmi2String name, const char *fmt, ...)
{
    va_list ap;
    char *text;
    if (f == NULL || f->logger == NULL) return;
    va_start(ap, fmt);
    text = vformat(fmt, ap);
    va_end(ap);
    {
        char *format = as_format(text ? text : "fmi2Instantiate failed");
        f->logger(f->componentEnvironment, name ? name : "", fmi2Error, "logStatusError", format ? format : "%s",
                  "fmi2Instantiate failed");
        free(format);
    }
    free(text);
}

/* UTF-8 bytes of str(obj), invalid code points replaced; a malloc'd C string, never NULL. */
static char *utf8_of(PyObject *obj)
{
    PyObject *text = obj && PyUnicode_Check(obj) ? (Py_INCREF(obj), obj) : (obj ? PyObject_Str(obj) : NULL);
    PyObject *bytes = text ? PyUnicode_AsEncodedString(text, "utf-8", "replace") : NULL;
    char *out;
    Py_XDECREF(text);
    if (bytes == NULL) {
        PyErr_Clear();
        return strdup("(a message that cannot be converted to text)");
    }
    out = strdup(PyBytes_AS_STRING(bytes));
    Py_DECREF(bytes);
    return out ? out : strdup("");
}

/* Is the exception type (a subclass of) parcosim's FmiError? */
static int is_fmi_error(PyObject *type)
{
    PyObject *mro;
    Py_ssize_t i;
    if (type == NULL || !PyType_Check(type)) return 0;
    mro = ((PyTypeObject *)type)->tp_mro;
    if (mro == NULL || !PyTuple_Check(mro)) return 0;
    for (i = 0; i < PyTuple_GET_SIZE(mro); i++) {
        const char *name = ((PyTypeObject *)PyTuple_GET_ITEM(mro, i))->tp_name;
        const char *dot = strrchr(name, '.');
        if (strcmp(dot ? dot + 1 : name, "FmiError") == 0) return 1;
    }
    return 0;
}

/* The pending Python exception as "Type: message" ("message" for an FmiError); clears it. */
static char *take_exception(void)
{
    PyObject *type, *value, *tb;
    char *message, *out;
    PyErr_Fetch(&type, &value, &tb);
    if (type == NULL) return strdup("failed without a Python exception");
    PyErr_NormalizeException(&type, &value, &tb);
    message = utf8_of(value ? value : Py_None);
    if (is_fmi_error(type)) {
        out = message;
    } else {
        const char *tname = PyType_Check(type) ? ((PyTypeObject *)type)->tp_name : "exception";
        size_t n = strlen(tname) + strlen(message) + 3;
        out = malloc(n);
        if (out) snprintf(out, n, "%s%s%s", tname, *message ? ": " : "", message);
        free(message);
    }
    Py_XDECREF(type);
    Py_XDECREF(value);
    Py_XDECREF(tb);
    PyErr_Clear();
    return out ? out : strdup("(out of memory)");
}

/* Forward the slave's queued log messages (pythonfmu's Fmi2Slave.log) and empty the queue. */
static void drain_log(Instance *in)
{
    PyObject *type, *value, *tb, *items;
    Py_ssize_t i, n;
    if (in->log_queue == NULL || !PyList_Check(in->log_queue) || PyList_GET_SIZE(in->log_queue) == 0) return;
    PyErr_Fetch(&type, &value, &tb);   /* keep a pending exception for the caller */
    n = PyList_GET_SIZE(in->log_queue);
    items = PyList_GetSlice(in->log_queue, 0, n);
    if (items != NULL && PyList_SetSlice(in->log_queue, 0, n, NULL) == 0) {
        for (i = 0; i < n; i++) {
            PyObject *item = PyList_GET_ITEM(items, i);
            PyObject *msg = PyObject_GetAttr(item, s_msg);
            PyObject *category = PyObject_GetAttr(item, s_category);
            PyObject *status = PyObject_GetAttr(item, s_status);
            long level = status ? PyLong_AsLong(status) : 0;
            char *text, *cat;
            PyErr_Clear();
            if (level < fmi2OK || level > fmi2Fatal) level = fmi2Error;
            if (level == fmi2Fatal) level = fmi2Error;   /* never fmi2Fatal */
            text = utf8_of(msg ? msg : item);
            cat = category && category != Py_None ? utf8_of(category) : strdup("logAll");
            emit(in, (fmi2Status)level, cat ? cat : "logAll", text);
            free(text);
            free(cat);
            Py_XDECREF(msg);
            Py_XDECREF(category);
            Py_XDECREF(status);
        }
    }
    Py_XDECREF(items);
    PyErr_Clear();
    PyErr_Restore(type, value, tb);
}

/* The pending exception turned into a logged fmi2Error of function fn. */
static fmi2Status failed(Instance *in, const char *fn)
{
    char *message = take_exception();
    drain_log(in);
    logf_(in, fmi2Error, "%s: %s (t = %.9g s)", fn, message, in->time);
    free(message);
    return fmi2Error;
}

/* ---- value references ---- */

static const char *kind_name(char kind)
{
    switch (kind) {
    case KIND_REAL: return "Real";
    case KIND_INTEGER: return "Integer";
    case KIND_BOOLEAN: return "Boolean";
    case KIND_STRING: return "String";
    default: return "unknown";
    }
}

/* slave.vars (value reference -> pythonfmu ScalarVariable) as a table of kinds. */
static int read_kinds(Instance *in)
{
    PyObject *vars = PyObject_GetAttr(in->slave, s_vars), *key, *var;
    Py_ssize_t pos = 0;
    size_t size = 0;
    char *kinds;
    if (vars == NULL) return -1;
    if (!PyDict_Check(vars)) {
        PyErr_SetString(PyExc_TypeError, "the slave's 'vars' is not a dict");
        Py_DECREF(vars);
        return -1;
    }
    while (PyDict_Next(vars, &pos, &key, &var)) {
        size_t vr = PyLong_AsSize_t(key);
        if (PyErr_Occurred()) { Py_DECREF(vars); return -1; }
        if (vr + 1 > size) size = vr + 1;
    }
    kinds = calloc(size ? size : 1, 1);
    if (kinds == NULL) { Py_DECREF(vars); PyErr_NoMemory(); return -1; }
    pos = 0;
    while (PyDict_Next(vars, &pos, &key, &var)) {
        size_t vr = PyLong_AsSize_t(key);
        char kind = KIND_NONE;
        if (PyObject_IsInstance(var, c_real) == 1) kind = KIND_REAL;
        else if (PyObject_IsInstance(var, c_integer) == 1) kind = KIND_INTEGER;
        else if (PyObject_IsInstance(var, c_boolean) == 1) kind = KIND_BOOLEAN;
        else if (PyObject_IsInstance(var, c_string) == 1) kind = KIND_STRING;
        PyErr_Clear();
        kinds[vr] = kind;
    }
    Py_DECREF(vars);
    free(in->kinds);
    in->kinds = kinds;
    in->n_kinds = size;
    return 0;
}

/* The variable's name for messages ("?" if it has none); a malloc'd string. */
static char *var_name(Instance *in, fmi2ValueReference vr)
{
    PyObject *vars = PyObject_GetAttr(in->slave, s_vars);
    PyObject *key = PyLong_FromUnsignedLong(vr);
    PyObject *var = vars && key ? PyObject_GetItem(vars, key) : NULL;
    PyObject *name = var ? PyObject_GetAttr(var, s_name) : NULL;
    char *out = name ? utf8_of(name) : strdup("?");
    Py_XDECREF(vars);
    Py_XDECREF(key);
    Py_XDECREF(var);
    Py_XDECREF(name);
    PyErr_Clear();
    return out;
}

/* 0 if every vr names a variable of this kind; else logs the first that does not, -1. */
static int check_vrs(Instance *in, const char *fn, const fmi2ValueReference vr[], size_t nvr, char kind)
{
    size_t i;
    int reread = 0;
    for (i = 0; i < nvr; i++) {
        char have = vr[i] < in->n_kinds ? in->kinds[vr[i]] : KIND_NONE;
        if (have == KIND_NONE && !reread) {   /* variables declared after instantiation */
            reread = 1;
            if (read_kinds(in) != 0) return failed(in, fn), -1;
            have = vr[i] < in->n_kinds ? in->kinds[vr[i]] : KIND_NONE;
        }
        if (have == KIND_NONE) {
            logf_(in, fmi2Error, "%s: value reference %u is not a variable of this FMU (t = %.9g s)",
                  fn, vr[i], in->time);
            return -1;
        }
        if (have != kind) {
            char *name = var_name(in, vr[i]);
            logf_(in, fmi2Error, "%s: value reference %u ('%s') is a %s variable, not a %s (t = %.9g s)",
                  fn, vr[i], name, kind_name(have), kind_name(kind), in->time);
            free(name);
            return -1;
        }
    }
    return 0;
}

static PyObject *vr_list(const fmi2ValueReference vr[], size_t nvr)
{
    PyObject *list = PyList_New((Py_ssize_t)nvr);
    size_t i;
    if (list == NULL) return NULL;
    for (i = 0; i < nvr; i++) {
        PyObject *item = PyLong_FromUnsignedLong(vr[i]);
        if (item == NULL) { Py_DECREF(list); return NULL; }
        PyList_SET_ITEM(list, (Py_ssize_t)i, item);
    }
    return list;
}

/* ---- Python ---- */

static PyObject *intern(const char *s) { return PyUnicode_InternFromString(s); }

/* Initialise Python if the host has not; 0 on success. */
static int ensure_python(const char **why)
{
    int ok = 1;
    pthread_mutex_lock(&init_lock);
    if (!Py_IsInitialized()) {
        PyConfig config;
        PyStatus status;
        PyConfig_InitPythonConfig(&config);
        config.install_signal_handlers = 0;   /* the host owns its signals */
        config.parse_argv = 0;
        status = Py_InitializeFromConfig(&config);
        PyConfig_Clear(&config);
        if (PyStatus_Exception(status) || !Py_IsInitialized()) {
            *why = status.err_msg ? status.err_msg : "Py_InitializeFromConfig failed";
            ok = 0;
        } else {
            PyEval_SaveThread();   /* release the GIL: every call takes it with PyGILState_Ensure */
        }
    }
    pthread_mutex_unlock(&init_lock);
    return ok ? 0 : -1;
}

/* The interned names and pythonfmu's classes (under the GIL); 0 on success. */
static int ensure_names(void)
{
    PyObject *module;
    if (c_string != NULL) return 0;
    s_get_real = intern("get_real"); s_get_integer = intern("get_integer");
    s_get_boolean = intern("get_boolean"); s_get_string = intern("get_string");
    s_set_real = intern("set_real"); s_set_integer = intern("set_integer");
    s_set_boolean = intern("set_boolean"); s_set_string = intern("set_string");
    s_do_step = intern("do_step"); s_setup_experiment = intern("setup_experiment");
    s_enter_init = intern("enter_initialization_mode"); s_exit_init = intern("exit_initialization_mode");
    s_terminate = intern("terminate"); s_get_fmu_state = intern("_get_fmu_state");
    s_set_fmu_state = intern("_set_fmu_state"); s_to_bytes = intern("_fmu_state_to_bytes");
    s_from_bytes = intern("_fmu_state_from_bytes"); s_deserialize = intern("deserialize_fmu_state"); s_msg = intern("msg"); s_category = intern("category");
    s_status = intern("status"); s_vars = intern("vars"); s_name = intern("name"); s_log_queue = intern("log_queue");
    if (PyErr_Occurred()) return -1;
    module = PyImport_ImportModule("pythonfmu.fmi2slave");
    if (module == NULL) return -1;
    c_fmi2slave = PyObject_GetAttrString(module, "Fmi2Slave");
    Py_DECREF(module);
    module = PyImport_ImportModule("pythonfmu.variables");
    if (module == NULL) return -1;
    c_real = PyObject_GetAttrString(module, "Real");
    c_integer = PyObject_GetAttrString(module, "Integer");
    c_boolean = PyObject_GetAttrString(module, "Boolean");
    c_string = PyObject_GetAttrString(module, "String");
    Py_DECREF(module);
    if (!c_fmi2slave || !c_real || !c_integer || !c_boolean || !c_string) {
        Py_CLEAR(c_string);   /* try again at the next instantiation */
        return -1;
    }
    return 0;
}

/* Decode a file URI (RFC 8089: file:///p, file:/p, file://localhost/p) into a malloc'd path.
 * A plain absolute path is taken as it is.  NULL with *why set if it is none of these. */
static char *uri_to_path(const char *uri, const char **why)
{
    const char *p;
    char *out, *o;
    if (uri == NULL) { *why = "no resource location (NULL)"; return NULL; }
    if (uri[0] == '/') return strdup(uri);
    if (strncmp(uri, "file:", 5) != 0) { *why = "not a file: URI"; return NULL; }
    p = uri + 5;
    if (strncmp(p, "//", 2) == 0) {
        p += 2;
        if (strncmp(p, "localhost/", 10) == 0) p += 9;
        else if (*p != '/') { *why = "a file URI with a host other than localhost"; return NULL; }
    } else if (*p != '/') {
        *why = "a file URI without an absolute path";
        return NULL;
    }
    out = o = malloc(strlen(p) + 1);
    if (out == NULL) { *why = "out of memory"; return NULL; }
    for (; *p; p++) {
        if (*p == '%') {
            int hi, lo, value;
            hi = p[1] ? (p[1] >= '0' && p[1] <= '9' ? p[1] - '0' : (p[1] | 32) >= 'a' && (p[1] | 32) <= 'f' ? (p[1] | 32) - 'a' + 10 : -1) : -1;
            lo = hi >= 0 && p[2] ? (p[2] >= '0' && p[2] <= '9' ? p[2] - '0' : (p[2] | 32) >= 'a' && (p[2] | 32) <= 'f' ? (p[2] | 32) - 'a' + 10 : -1) : -1;
            if (hi < 0 || lo < 0) { free(out); *why = "a '%' not followed by two hexadecimal digits"; return NULL; }
            value = hi * 16 + lo;
            if (value == 0) { free(out); *why = "%00 (a NUL byte) in the path"; return NULL; }
            *o++ = (char)value;
            p += 2;
        } else if (*p == '?' || *p == '#') {
            break;   /* a query or fragment is not part of the path */
        } else {
            *o++ = *p;
        }
    }
    *o = '\0';
    return out;
}

/* Which slave class an instantiation runs; executed once per wrapper library (per FMU type). */
static const char LOADER_SOURCE[] =
"import importlib, importlib.util, json, os, sys\n"
"IDENTITY = 'parcosim_build.json'\n"
"class FmiError(Exception):\n"
"    'Refuses the instantiation; its message alone is logged.'\n"
"def slave_class(resources, guid, identifier, base):\n"
"    'The Fmi2Slave subclass of the FMU of resources, checked against the GUID given and this binary.'\n"
"    identity = read_identity(resources, identifier)\n"
"    own = identity.get('guid')\n"
"    if identity.get('model_identifier') != identifier:\n"
"        raise FmiError(f'the resources {resources} belong to the FMU {identity.get(\"model_identifier\")!r} '\n"
"                       f'(GUID {own!r}), not to this binary ({identifier}): resources of another FMU refused')\n"
"    if guid != own:\n"
"        raise FmiError(f'GUID {guid!r} is not this FMU\\'s: {identifier} has GUID {own!r} '\n"
"                       f'({os.path.join(resources, IDENTITY)})')\n"
"    name = slave_module(resources)\n"
"    package = identity.get('package')\n"
"    if package:\n"
"        if not name.startswith(package + '.'):\n"
"            raise FmiError(f'slavemodule.txt names {name!r}, not a module of the bundle {package!r}')\n"
"        attach(package, os.path.join(resources, package))\n"
"    elif resources not in sys.path:\n"
"        sys.path.insert(0, resources)   # a pythonfmu slave without a bundle: as pythonfmu imports it\n"
"    return deepest_subclass(importlib.import_module(name), base)\n"
"def read_identity(resources, identifier):\n"
"    path = os.path.join(resources, IDENTITY)\n"
"    try:\n"
"        with open(path, encoding='utf-8') as f:\n"
"            identity = json.load(f)\n"
"    except (OSError, ValueError) as exc:\n"
"        raise FmiError(f'no identity of the FMU ({exc}): the resources {resources} are not those of '\n"
"                       f'{identifier}, an FMU with parcosim\\'s wrapper') from None\n"
"    if not isinstance(identity, dict):\n"
"        raise FmiError(f'{path} is not a JSON object')\n"
"    return identity\n"
"def slave_module(resources):\n"
"    path = os.path.join(resources, 'slavemodule.txt')\n"
"    try:\n"
"        with open(path, encoding='utf-8') as f:\n"
"            name = f.readline().strip()\n"
"    except (OSError, ValueError) as exc:\n"
"        raise FmiError(f'cannot read {path} (the slave\\'s module name): {exc}') from None\n"
"    if not all(part.isidentifier() for part in name.split('.')):\n"
"        raise FmiError(f'slavemodule.txt names {name!r}, not a Python module')\n"
"    return name\n"
"def attach(package, folder):\n"
"    # The bundle under its private name, from folder, without sys.path.  Loaded already (another\n"
"    # FMU of the same build): its packages also look in folder, and no more in folders that are\n"
"    # gone (an importer deletes an extraction when it is done with it).\n"
"    if not os.path.isfile(os.path.join(folder, '__init__.py')):\n"
"        raise FmiError(f'the bundle {package} is missing from the resources ({folder})')\n"
"    loaded = sys.modules.get(package)\n"
"    if loaded is None:\n"
"        spec = importlib.util.spec_from_file_location(package, os.path.join(folder, '__init__.py'),\n"
"                                                      submodule_search_locations=[folder])\n"
"        module = importlib.util.module_from_spec(spec)\n"
"        sys.modules[package] = module\n"
"        try:\n"
"            spec.loader.exec_module(module)\n"
"        except BaseException:\n"
"            del sys.modules[package]\n"
"            raise\n"
"        return\n"
"    for name, module in list(sys.modules.items()):\n"
"        path = getattr(module, '__path__', None)\n"
"        if (name == package or name.startswith(package + '.')) and isinstance(path, list):\n"
"            own = os.path.join(folder, *name.split('.')[1:])\n"
"            path[:] = [p for p in path if p != own and os.path.isdir(p)] + [own]\n"
"def deepest_subclass(module, base):\n"
"    'The subclass of base deepest below it, preferring those the module defines (as pythonfmu).'\n"
"    found = [c for c in vars(module).values() if isinstance(c, type) and c is not base and issubclass(c, base)]\n"
"    local = [c for c in found if c.__module__ == module.__name__] or found\n"
"    if not local:\n"
"        raise FmiError(f'module {module.__name__} defines no pythonfmu Fmi2Slave subclass')\n"
"    return max(local, key=lambda c: c.__mro__.index(base))\n";

/* The loader's slave_class, compiled from LOADER_SOURCE once (under the GIL); 0 on success. */
static int ensure_loader(void)
{
    PyObject *module, *code, *result;
    if (loader_slave_class != NULL) return 0;
    module = PyModule_New("parcosim_fmi2_loader");
    code = module ? Py_CompileString(LOADER_SOURCE, "<parcosim_fmi2 loader>", Py_file_input) : NULL;
    if (code != NULL && PyModule_AddObjectRef(module, "__builtins__", PyEval_GetBuiltins()) == 0) {
        result = PyEval_EvalCode(code, PyModule_GetDict(module), PyModule_GetDict(module));
        Py_XDECREF(result);
        if (result != NULL) loader_slave_class = PyObject_GetAttrString(module, "slave_class");
    }
    Py_XDECREF(code);
    Py_XDECREF(module);
    return loader_slave_class != NULL ? 0 : -1;
}

/* The process-wide lock every parcosim wrapper library shares: a recursive mutex whose address
 * the first library that needs it keeps in sys.modules["_parcosim_fmi2"].python_lock (under the
 * GIL, which nothing here releases in between: no race).  An address, not a capsule: a capsule's
 * name would point into this library, which the importer may unload while others run on.  NULL
 * only when out of memory. */
static pthread_mutex_t *shared_lock(void)
{
    PyObject *modules = PySys_GetObject("modules"), *holder, *address;   /* borrowed */
    PyObject *type, *value, *tb;
    if (python_lock != NULL) return python_lock;
    if (modules == NULL || !PyDict_Check(modules)) return NULL;
    PyErr_Fetch(&type, &value, &tb);
    holder = PyDict_GetItemString(modules, "_parcosim_fmi2");   /* borrowed */
    if (holder == NULL) {
        pthread_mutex_t *lock = malloc(sizeof *lock);   /* never freed: every library may use it */
        PyObject *made = PyModule_New("_parcosim_fmi2");
        address = made && lock ? PyLong_FromVoidPtr(lock) : NULL;
        if (address != NULL) {
            pthread_mutexattr_t attr;
            pthread_mutexattr_init(&attr);
            pthread_mutexattr_settype(&attr, PTHREAD_MUTEX_RECURSIVE);
            pthread_mutex_init(lock, &attr);
            pthread_mutexattr_destroy(&attr);
        }
        if (address != NULL && PyModule_AddObjectRef(made, "python_lock", address) == 0 &&
            PyDict_SetItemString(modules, "_parcosim_fmi2", made) == 0)
            python_lock = lock;
        else
            free(lock);
        Py_XDECREF(address);
        Py_XDECREF(made);
    } else {
        address = PyObject_GetAttrString(holder, "python_lock");
        python_lock = address ? PyLong_AsVoidPtr(address) : NULL;
        Py_XDECREF(address);
    }
    PyErr_Clear();
    PyErr_Restore(type, value, tb);
    return python_lock;
}

/* Take the GIL, then the shared lock; waiting for the lock releases the GIL, so the thread
 * that holds the lock can always go on (no deadlock between the two). */
static PyGILState_STATE enter_python(void)
{
    PyGILState_STATE gil = PyGILState_Ensure();
    pthread_mutex_t *lock = shared_lock();
    if (lock != NULL && pthread_mutex_trylock(lock) != 0) {
        Py_BEGIN_ALLOW_THREADS
        pthread_mutex_lock(lock);
        Py_END_ALLOW_THREADS
    }
    return gil;
}

static void leave_python(PyGILState_STATE gil)
{
    if (python_lock != NULL) pthread_mutex_unlock(python_lock);
    PyGILState_Release(gil);
}

/* This library's modelIdentifier: its file name without the extension (a malloc'd string). */
static char *own_identifier(void)
{
    Dl_info info;
    const char *name, *slash, *dot;
    char *out;
    if (dladdr((void *)own_identifier, &info) == 0 || info.dli_fname == NULL) return strdup("");
    slash = strrchr(info.dli_fname, '/');
    name = slash ? slash + 1 : info.dli_fname;
    dot = strrchr(name, '.');
    out = strndup(name, dot ? (size_t)(dot - name) : strlen(name));
    return out ? out : strdup("");
}

static void free_instance(Instance *in)
{
    size_t i;
    if (in == NULL) return;
    if (Py_IsInitialized()) {
        PyGILState_STATE gil = PyGILState_Ensure();
        if (in->slave) drain_log(in);
        Py_CLEAR(in->strings);
        Py_CLEAR(in->log_queue);
        Py_CLEAR(in->slave);
        Py_CLEAR(in->cls);
        Py_CLEAR(in->kwargs);
        PyGILState_Release(gil);
    }
    for (i = 0; i < in->n_categories; i++) free(in->categories[i]);
    free(in->categories);
    free(in->kinds);
    free(in->name);
    free(in);
}

/* Create the slave object from in->cls and in->kwargs; 0 on success (Python error set otherwise). */
static int make_slave(Instance *in)
{
    PyObject *empty = PyTuple_New(0), *slave, *queue;
    if (empty == NULL) return -1;
    slave = PyObject_Call(in->cls, empty, in->kwargs);
    Py_DECREF(empty);
    if (slave == NULL) return -1;
    queue = PyObject_GetAttr(slave, s_log_queue);
    if (queue == NULL) { Py_DECREF(slave); return -1; }
    Py_XSETREF(in->slave, slave);
    Py_XSETREF(in->log_queue, queue);
    Py_CLEAR(in->strings);
    return read_kinds(in);
}

/* ---- the FMI 2.0 API ---- */

EXPORT const char *fmi2GetTypesPlatform(void) { return "default"; }
EXPORT const char *fmi2GetVersion(void) { return "2.0"; }

EXPORT fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                                     fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                                     fmi2Boolean visible, fmi2Boolean loggingOn)
{
    const char *why = NULL;
    char *resources, *identifier = NULL;
    Instance *in;
    PyGILState_STATE gil;
    PyObject *py_resources = NULL, *py_guid = NULL, *py_identifier = NULL, *py_name = NULL, *ptr = NULL;
    if (instanceName == NULL) {
        log_instantiate(functions, "", "fmi2Instantiate: the instance name is NULL");
        return NULL;
    }
    if (fmuType != fmi2CoSimulation) {
        log_instantiate(functions, instanceName, "fmi2Instantiate: this FMU supports co-simulation only (fmuType = %d)",
                        (int)fmuType);
        return NULL;
    }
    resources = uri_to_path(fmuResourceLocation, &why);
    if (resources == NULL) {
        log_instantiate(functions, instanceName, "fmi2Instantiate: resource location '%s' refused: %s",
                        fmuResourceLocation ? fmuResourceLocation : "(NULL)", why);
        return NULL;
    }
    { /* strip trailing slashes (not the root) */
        size_t n = strlen(resources);
        while (n > 1 && resources[n - 1] == '/') resources[--n] = '\0';
    }
    if (ensure_python(&why) != 0) {
        log_instantiate(functions, instanceName, "fmi2Instantiate: Python cannot be initialised: %s", why);
        free(resources);
        return NULL;
    }
    in = calloc(1, sizeof *in);
    if (in == NULL || (in->name = strdup(instanceName)) == NULL) {
        free(in);
        free(resources);
        log_instantiate(functions, instanceName, "fmi2Instantiate: out of memory");
        return NULL;
    }
    if (functions != NULL) {
        in->logger = functions->logger;
        in->env = functions->componentEnvironment;
    }
    in->logging_on = loggingOn != fmi2False;

    gil = enter_python();   /* the import and the slave's creation under the shared lock */
    if (ensure_names() != 0 || ensure_loader() != 0) goto python_failed;
    identifier = own_identifier();
    py_resources = PyUnicode_DecodeFSDefault(resources);
    py_guid = fmuGUID ? PyUnicode_DecodeUTF8(fmuGUID, (Py_ssize_t)strlen(fmuGUID), "replace") : Py_NewRef(Py_None);
    py_identifier = identifier ? PyUnicode_DecodeFSDefault(identifier) : NULL;
    if (py_resources == NULL || py_guid == NULL || py_identifier == NULL) goto python_failed;
    in->cls = PyObject_CallFunctionObjArgs(loader_slave_class, py_resources, py_guid, py_identifier, c_fmi2slave,
                                           NULL);
    if (in->cls == NULL) goto python_failed;
    py_name = PyUnicode_DecodeUTF8(instanceName, (Py_ssize_t)strlen(instanceName), "replace");
    ptr = PyLong_FromVoidPtr((void *)functions);
    if (py_name == NULL || ptr == NULL) goto python_failed;
    in->kwargs = Py_BuildValue("{sOsOsOsO}", "instance_name", py_name, "resources", py_resources,
                               "visible", visible ? Py_True : Py_False, "logger", ptr);
    if (in->kwargs == NULL || make_slave(in) != 0) goto python_failed;
    drain_log(in);
    Py_DECREF(py_resources);
    Py_DECREF(py_guid);
    Py_DECREF(py_identifier);
    Py_DECREF(py_name);
    Py_DECREF(ptr);
    leave_python(gil);
    free(resources);
    free(identifier);
    return in;

python_failed:
    {
        char *message = take_exception();
        if (in->slave) drain_log(in);
        logf_(in, fmi2Error, "fmi2Instantiate: %s (resources %s)", message, resources);
        free(message);
    }
    Py_XDECREF(py_resources);
    Py_XDECREF(py_guid);
    Py_XDECREF(py_identifier);
    Py_XDECREF(py_name);
    Py_XDECREF(ptr);
    leave_python(gil);
    free(resources);
    free(identifier);
    free_instance(in);
    return NULL;
}

EXPORT void fmi2FreeInstance(fmi2Component c) { free_instance((Instance *)c); }

EXPORT fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                                      const fmi2String categories[])
{
    Instance *in = (Instance *)c;
    size_t i, n = 0;
    char **copy = NULL;
    if (in == NULL) return fmi2Error;
    if (nCategories > 0 && categories == NULL) {
        logf_(in, fmi2Error, "fmi2SetDebugLogging: %zu categories but no array (NULL)", nCategories);
        return fmi2Error;
    }
    if (nCategories > 0 && (copy = calloc(nCategories, sizeof *copy)) == NULL) return fmi2Error;
    for (i = 0; i < nCategories; i++)
        if (categories[i] != NULL && (copy[n] = strdup(categories[i])) != NULL) n++;
    for (i = 0; i < in->n_categories; i++) free(in->categories[i]);
    free(in->categories);
    in->categories = copy;
    in->n_categories = n;
    in->logging_on = loggingOn != fmi2False;
    return fmi2OK;
}

/* Call slave.<method>(*args) under the GIL: fmi2OK, or a logged fmi2Error. */
static fmi2Status call0(Instance *in, const char *fn, PyObject *method, PyObject *arg1, PyObject *arg2,
                        PyObject *arg3)
{
    PyGILState_STATE gil;
    PyObject *result;
    fmi2Status status = fmi2OK;
    if (in == NULL) return fmi2Error;
    gil = enter_python();
    if (arg1 && arg2 && arg3) result = PyObject_CallMethodObjArgs(in->slave, method, arg1, arg2, arg3, NULL);
    else result = PyObject_CallMethodNoArgs(in->slave, method);
    if (result == NULL) status = failed(in, fn);
    else drain_log(in);
    Py_XDECREF(result);
    leave_python(gil);
    return status;
}

EXPORT fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                                      fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    Instance *in = (Instance *)c;
    PyGILState_STATE gil;
    PyObject *start, *stop, *tol;
    fmi2Status status;
    if (in == NULL) return fmi2Error;
    gil = enter_python();
    start = PyFloat_FromDouble(startTime);
    stop = stopTimeDefined ? PyFloat_FromDouble(stopTime) : Py_NewRef(Py_None);
    tol = toleranceDefined ? PyFloat_FromDouble(tolerance) : Py_NewRef(Py_None);
    if (start && stop && tol) status = call0(in, "fmi2SetupExperiment", s_setup_experiment, start, stop, tol);
    else status = failed(in, "fmi2SetupExperiment");
    if (status == fmi2OK) in->time = in->last_successful_time = startTime;   /* a refusal changes nothing */
    Py_XDECREF(start);
    Py_XDECREF(stop);
    Py_XDECREF(tol);
    leave_python(gil);
    return status;
}

EXPORT fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    return call0((Instance *)c, "fmi2EnterInitializationMode", s_enter_init, NULL, NULL, NULL);
}

EXPORT fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    return call0((Instance *)c, "fmi2ExitInitializationMode", s_exit_init, NULL, NULL, NULL);
}

EXPORT fmi2Status fmi2Terminate(fmi2Component c)
{
    return call0((Instance *)c, "fmi2Terminate", s_terminate, NULL, NULL, NULL);
}

EXPORT fmi2Status fmi2Reset(fmi2Component c)
{
    Instance *in = (Instance *)c;
    PyGILState_STATE gil;
    fmi2Status status = fmi2OK;
    if (in == NULL) return fmi2Error;
    gil = enter_python();
    drain_log(in);
    if (make_slave(in) != 0) status = failed(in, "fmi2Reset");   /* the old slave stays if creating fails */
    else drain_log(in);
    in->time = in->last_successful_time = 0.0;
    leave_python(gil);
    return status;
}

/* Common entry of the array functions: NULL checks. */
static int arrays_ok(Instance *in, const char *fn, const void *vr, const void *values, size_t nvr)
{
    if (nvr == 0) return 1;
    if (vr == NULL || values == NULL) {
        logf_(in, fmi2Error, "%s: %s is NULL for %zu value references (t = %.9g s)", fn,
              vr == NULL ? "the value reference array" : "the value array", nvr, in->time);
        return 0;
    }
    return 1;
}

/* slave.<getter>(vrs) as a sequence of exactly nvr items (new reference via PySequence_Fast), or NULL. */
static PyObject *get_values(Instance *in, const char *fn, PyObject *getter, const fmi2ValueReference vr[],
                            size_t nvr)
{
    PyObject *vrs = vr_list(vr, nvr), *result, *seq;
    if (vrs == NULL) return NULL;
    result = PyObject_CallMethodOneArg(in->slave, getter, vrs);
    Py_DECREF(vrs);
    if (result == NULL) return NULL;
    seq = PySequence_Fast(result, "the getter did not return a sequence");
    Py_DECREF(result);
    if (seq != NULL && (size_t)PySequence_Fast_GET_SIZE(seq) != nvr) {
        PyErr_Format(PyExc_ValueError, "%s returned %zd values for %zu value references", fn,
                     PySequence_Fast_GET_SIZE(seq), nvr);
        Py_CLEAR(seq);
    }
    (void)fn;
    return seq;
}

#define GETTER_PROLOGUE(KIND, FN)                                                          \
    Instance *in = (Instance *)c;                                                          \
    PyGILState_STATE gil;                                                                  \
    PyObject *seq;                                                                         \
    fmi2Status status = fmi2OK;                                                            \
    size_t i;                                                                              \
    if (in == NULL) return fmi2Error;                                                      \
    if (!arrays_ok(in, FN, vr, value, nvr)) return fmi2Error;                              \
    if (nvr == 0) return fmi2OK;                                                           \
    gil = enter_python();                                                                  \
    if (check_vrs(in, FN, vr, nvr, KIND) != 0) { leave_python(gil); return fmi2Error; }

EXPORT fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[])
{
    GETTER_PROLOGUE(KIND_REAL, "fmi2GetReal")
    seq = get_values(in, "fmi2GetReal", s_get_real, vr, nvr);
    for (i = 0; seq && i < nvr; i++) {
        double v = PyFloat_AsDouble(PySequence_Fast_GET_ITEM(seq, i));
        if (v == -1.0 && PyErr_Occurred()) break;
        value[i] = v;
    }
    if (seq == NULL || PyErr_Occurred()) status = failed(in, "fmi2GetReal");
    else drain_log(in);
    Py_XDECREF(seq);
    leave_python(gil);
    return status;
}

EXPORT fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[])
{
    GETTER_PROLOGUE(KIND_INTEGER, "fmi2GetInteger")
    seq = get_values(in, "fmi2GetInteger", s_get_integer, vr, nvr);
    for (i = 0; seq && i < nvr; i++) {
        long v = PyLong_AsLong(PySequence_Fast_GET_ITEM(seq, i));
        if (v == -1 && PyErr_Occurred()) break;
        if (v < -2147483647L - 1 || v > 2147483647L) {
            char *name = var_name(in, vr[i]);
            PyErr_Format(PyExc_OverflowError, "%s = %ld does not fit an fmi2Integer", name, v);
            free(name);
            break;
        }
        value[i] = (fmi2Integer)v;
    }
    if (seq == NULL || PyErr_Occurred()) status = failed(in, "fmi2GetInteger");
    else drain_log(in);
    Py_XDECREF(seq);
    leave_python(gil);
    return status;
}

EXPORT fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[])
{
    GETTER_PROLOGUE(KIND_BOOLEAN, "fmi2GetBoolean")
    seq = get_values(in, "fmi2GetBoolean", s_get_boolean, vr, nvr);
    for (i = 0; seq && i < nvr; i++) {
        int v = PyObject_IsTrue(PySequence_Fast_GET_ITEM(seq, i));
        if (v < 0) break;
        value[i] = v ? fmi2True : fmi2False;
    }
    if (seq == NULL || PyErr_Occurred()) status = failed(in, "fmi2GetBoolean");
    else drain_log(in);
    Py_XDECREF(seq);
    leave_python(gil);
    return status;
}

EXPORT fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[])
{
    PyObject *strings = NULL;
    GETTER_PROLOGUE(KIND_STRING, "fmi2GetString")
    seq = get_values(in, "fmi2GetString", s_get_string, vr, nvr);
    if (seq != NULL) strings = PyList_New((Py_ssize_t)nvr);
    for (i = 0; seq && strings && i < nvr; i++) {
        PyObject *item = PySequence_Fast_GET_ITEM(seq, i);
        PyObject *text = PyUnicode_Check(item) ? Py_NewRef(item) : PyObject_Str(item);
        PyObject *bytes = text ? PyUnicode_AsEncodedString(text, "utf-8", "replace") : NULL;
        Py_XDECREF(text);
        if (bytes == NULL) break;
        PyList_SET_ITEM(strings, (Py_ssize_t)i, bytes);
    }
    if (seq == NULL || strings == NULL || PyErr_Occurred()) {
        Py_XDECREF(strings);
        status = failed(in, "fmi2GetString");
    } else {
        for (i = 0; i < nvr; i++) value[i] = PyBytes_AS_STRING(PyList_GET_ITEM(strings, (Py_ssize_t)i));
        Py_XSETREF(in->strings, strings);   /* valid until the next fmi2GetString */
        drain_log(in);
    }
    Py_XDECREF(seq);
    leave_python(gil);
    return status;
}

/* slave.<setter>(vrs, values) with values already a list: fmi2OK or a logged fmi2Error. */
static fmi2Status set_values(Instance *in, const char *fn, PyObject *setter, const fmi2ValueReference vr[],
                             size_t nvr, PyObject *values)
{
    PyObject *vrs = values ? vr_list(vr, nvr) : NULL, *result = NULL;
    if (vrs != NULL) result = PyObject_CallMethodObjArgs(in->slave, setter, vrs, values, NULL);
    Py_XDECREF(vrs);
    Py_XDECREF(values);
    if (result == NULL) return failed(in, fn);
    Py_DECREF(result);
    drain_log(in);
    return fmi2OK;
}

#define SETTER(NAME, CTYPE, KIND, METHOD, CONVERT)                                                          \
    EXPORT fmi2Status NAME(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const CTYPE value[]) \
    {                                                                                                       \
        Instance *in = (Instance *)c;                                                                       \
        PyGILState_STATE gil;                                                                               \
        PyObject *values;                                                                                   \
        fmi2Status status;                                                                                  \
        size_t i;                                                                                           \
        if (in == NULL) return fmi2Error;                                                                   \
        if (!arrays_ok(in, #NAME, vr, value, nvr)) return fmi2Error;                                        \
        if (nvr == 0) return fmi2OK;                                                                        \
        gil = enter_python();                                                                               \
        if (check_vrs(in, #NAME, vr, nvr, KIND) != 0) { leave_python(gil); return fmi2Error; }        \
        values = PyList_New((Py_ssize_t)nvr);                                                               \
        for (i = 0; values && i < nvr; i++) {                                                               \
            PyObject *item = CONVERT(value[i]);                                                             \
            if (item == NULL) { Py_CLEAR(values); break; }                                                  \
            PyList_SET_ITEM(values, (Py_ssize_t)i, item);                                                   \
        }                                                                                                   \
        status = set_values(in, #NAME, METHOD, vr, nvr, values);                                            \
        leave_python(gil);                                                                            \
        return status;                                                                                      \
    }

#define BOOL_OBJECT(v) PyBool_FromLong((v) != fmi2False)
SETTER(fmi2SetReal, fmi2Real, KIND_REAL, s_set_real, PyFloat_FromDouble)
SETTER(fmi2SetInteger, fmi2Integer, KIND_INTEGER, s_set_integer, PyLong_FromLong)
SETTER(fmi2SetBoolean, fmi2Boolean, KIND_BOOLEAN, s_set_boolean, BOOL_OBJECT)

EXPORT fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[])
{
    Instance *in = (Instance *)c;
    PyGILState_STATE gil;
    PyObject *values;
    fmi2Status status;
    size_t i;
    if (in == NULL) return fmi2Error;
    if (!arrays_ok(in, "fmi2SetString", vr, value, nvr)) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    gil = enter_python();
    if (check_vrs(in, "fmi2SetString", vr, nvr, KIND_STRING) != 0) { leave_python(gil); return fmi2Error; }
    values = PyList_New((Py_ssize_t)nvr);
    for (i = 0; values && i < nvr; i++) {
        PyObject *item;
        char *name;
        if (value[i] == NULL) {
            name = var_name(in, vr[i]);
            logf_(in, fmi2Error, "fmi2SetString: the value of '%s' (value reference %u) is NULL (t = %.9g s)",
                  name, vr[i], in->time);
            free(name);
            Py_DECREF(values);
            leave_python(gil);
            return fmi2Error;
        }
        item = PyUnicode_DecodeUTF8(value[i], (Py_ssize_t)strlen(value[i]), "strict");
        if (item == NULL) {
            PyObject *type, *exc, *tb;
            Py_ssize_t at = -1;
            PyErr_Fetch(&type, &exc, &tb);
            PyErr_NormalizeException(&type, &exc, &tb);
            if (exc != NULL) PyUnicodeDecodeError_GetStart(exc, &at);
            Py_XDECREF(type); Py_XDECREF(exc); Py_XDECREF(tb);
            PyErr_Clear();
            name = var_name(in, vr[i]);
            logf_(in, fmi2Error, "fmi2SetString: the value of '%s' (value reference %u) is not UTF-8 "
                  "(invalid byte 0x%02x at offset %zd); the value is unchanged (t = %.9g s)",
                  name, vr[i], at >= 0 ? (unsigned char)value[i][at] : 0u, at, in->time);
            free(name);
            Py_DECREF(values);
            leave_python(gil);
            return fmi2Error;
        }
        PyList_SET_ITEM(values, (Py_ssize_t)i, item);
    }
    status = set_values(in, "fmi2SetString", s_set_string, vr, nvr, values);
    leave_python(gil);
    return status;
}

EXPORT fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                             fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    Instance *in = (Instance *)c;
    PyGILState_STATE gil;
    PyObject *t, *h, *result = NULL;
    fmi2Status status;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (in == NULL) return fmi2Error;
    gil = enter_python();
    in->time = currentCommunicationPoint;
    t = PyFloat_FromDouble(currentCommunicationPoint);
    h = PyFloat_FromDouble(communicationStepSize);
    if (t && h) result = PyObject_CallMethodObjArgs(in->slave, s_do_step, t, h, NULL);
    Py_XDECREF(t);
    Py_XDECREF(h);
    if (result == NULL) {
        status = failed(in, "fmi2DoStep");
    } else {
        int ok = PyObject_IsTrue(result);
        Py_DECREF(result);
        if (ok < 0) {
            status = failed(in, "fmi2DoStep");
        } else {
            drain_log(in);
            status = ok ? fmi2OK : fmi2Discard;
            if (ok) in->time = in->last_successful_time = currentCommunicationPoint + communicationStepSize;
        }
    }
    leave_python(gil);
    return status;
}

EXPORT fmi2Status fmi2CancelStep(fmi2Component c)
{
    logf_((Instance *)c, fmi2Error, "fmi2CancelStep: no step is pending (this FMU steps synchronously)");
    return fmi2Error;
}

/* fmi2Get*Status: this FMU never returns fmi2Pending, so only the last successful time and
 * "terminated" (never) are known; the rest is fmi2Discard ("not available"), as FMI 2.0 says. */
EXPORT fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value)
{
    (void)c; (void)s; (void)value;
    return c ? fmi2Discard : fmi2Error;
}

EXPORT fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
{
    Instance *in = (Instance *)c;
    if (in == NULL || value == NULL) return fmi2Error;
    if (s != fmi2LastSuccessfulTime) return fmi2Discard;
    *value = in->last_successful_time;
    return fmi2OK;
}

EXPORT fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value)
{
    (void)s; (void)value;
    return c ? fmi2Discard : fmi2Error;
}

EXPORT fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value)
{
    if (c == NULL || value == NULL) return fmi2Error;
    if (s != fmi2Terminated) return fmi2Discard;
    *value = fmi2False;   /* the slave never asks to end the simulation */
    return fmi2OK;
}

EXPORT fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value)
{
    (void)s; (void)value;
    return c ? fmi2Discard : fmi2Error;
}

static fmi2Status unsupported(fmi2Component c, const char *fn)
{
    logf_((Instance *)c, fmi2Error, "%s is not supported by this FMU", fn);
    return fmi2Error;
}

EXPORT fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                               size_t nUnknown, const fmi2ValueReference vKnown_ref[], size_t nKnown,
                                               const fmi2Real dvKnown[], fmi2Real dvUnknown[])
{
    (void)vUnknown_ref; (void)nUnknown; (void)vKnown_ref; (void)nKnown; (void)dvKnown; (void)dvUnknown;
    return unsupported(c, "fmi2GetDirectionalDerivative");
}

EXPORT fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                              const fmi2Integer order[], const fmi2Real value[])
{
    (void)vr; (void)nvr; (void)order; (void)value;
    return unsupported(c, "fmi2SetRealInputDerivatives");
}

EXPORT fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                               const fmi2Integer order[], fmi2Real value[])
{
    (void)vr; (void)nvr; (void)order; (void)value;
    return unsupported(c, "fmi2GetRealOutputDerivatives");
}

/* ---- FMU state ---- */

static State *as_state(Instance *in, const char *fn, fmi2FMUstate s)
{
    State *state = (State *)s;
    if (state == NULL || state->magic != STATE_MAGIC || state->owner != in) {
        logf_(in, fmi2Error, "%s: %s (t = %.9g s); nothing was changed", fn,
              state == NULL ? "the FMU state is NULL"
              : state->magic != STATE_MAGIC ? "not a live FMU state of this wrapper"
              : "the FMU state was issued by another instance (fmi2GetFMUstate or fmi2DeSerializeFMUstate of "
                "this instance make the states it takes)", in->time);
        return NULL;
    }
    return state;
}

static void drop_state(State *state)
{
    state->magic = 0;
    Py_CLEAR(state->state);
    Py_CLEAR(state->serialized);
    free(state);
}

/* *FMUstate holds the new Python state (reusing the struct already there, if any). */
static fmi2Status store_state(Instance *in, const char *fn, fmi2FMUstate *FMUstate, PyObject *value)
{
    State *state = *FMUstate ? as_state(in, fn, *FMUstate) : calloc(1, sizeof(State));
    if (state == NULL) {
        Py_DECREF(value);
        if (*FMUstate == NULL) logf_(in, fmi2Error, "%s: out of memory", fn);
        return fmi2Error;
    }
    state->magic = STATE_MAGIC;
    state->owner = in;
    Py_XSETREF(state->state, value);
    Py_CLEAR(state->serialized);
    *FMUstate = state;
    return fmi2OK;
}

EXPORT fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    Instance *in = (Instance *)c;
    PyGILState_STATE gil;
    PyObject *value;
    fmi2Status status;
    if (in == NULL) return fmi2Error;
    if (FMUstate == NULL) {
        logf_(in, fmi2Error, "fmi2GetFMUstate: the FMUstate pointer is NULL");
        return fmi2Error;
    }
    gil = enter_python();
    value = PyObject_CallMethodNoArgs(in->slave, s_get_fmu_state);
    if (value == NULL) status = failed(in, "fmi2GetFMUstate");
    else { drain_log(in); status = store_state(in, "fmi2GetFMUstate", FMUstate, value); }
    leave_python(gil);
    return status;
}

EXPORT fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate)
{
    Instance *in = (Instance *)c;
    PyGILState_STATE gil;
    State *state;
    PyObject *result;
    fmi2Status status = fmi2OK;
    if (in == NULL) return fmi2Error;
    gil = enter_python();
    state = as_state(in, "fmi2SetFMUstate", FMUstate);
    if (state == NULL) {
        leave_python(gil);
        return fmi2Error;
    }
    result = PyObject_CallMethodOneArg(in->slave, s_set_fmu_state, state->state);
    if (result == NULL) status = failed(in, "fmi2SetFMUstate");
    else drain_log(in);
    Py_XDECREF(result);
    leave_python(gil);
    return status;
}

EXPORT fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    Instance *in = (Instance *)c;
    PyGILState_STATE gil;
    State *state;
    if (in == NULL) return fmi2Error;
    if (FMUstate == NULL || *FMUstate == NULL) return fmi2OK;   /* FMI 2.0: freeing NULL is allowed */
    gil = enter_python();
    state = as_state(in, "fmi2FreeFMUstate", *FMUstate);
    if (state != NULL) drop_state(state);
    leave_python(gil);
    if (state == NULL) return fmi2Error;
    *FMUstate = NULL;
    return fmi2OK;
}

/* The state's serialised bytes (cached in the state), or NULL after a logged error. */
static PyObject *serialized(Instance *in, const char *fn, State *state)
{
    if (state->serialized == NULL) {
        PyObject *bytes = PyObject_CallMethodOneArg(in->cls, s_to_bytes, state->state);
        if (bytes != NULL && !PyBytes_Check(bytes)) {
            PyErr_Format(PyExc_TypeError, "_fmu_state_to_bytes returned %s, not bytes", Py_TYPE(bytes)->tp_name);
            Py_CLEAR(bytes);
        }
        if (bytes == NULL) {
            failed(in, fn);
            return NULL;
        }
        drain_log(in);
        state->serialized = bytes;
    }
    return state->serialized;
}

EXPORT fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size)
{
    Instance *in = (Instance *)c;
    PyGILState_STATE gil;
    State *state;
    PyObject *bytes = NULL;
    if (in == NULL) return fmi2Error;
    if (size == NULL) {
        logf_(in, fmi2Error, "fmi2SerializedFMUstateSize: the size pointer is NULL");
        return fmi2Error;
    }
    gil = enter_python();
    state = as_state(in, "fmi2SerializedFMUstateSize", FMUstate);
    if (state != NULL) bytes = serialized(in, "fmi2SerializedFMUstateSize", state);
    if (bytes != NULL) *size = (size_t)PyBytes_GET_SIZE(bytes);
    leave_python(gil);
    return bytes ? fmi2OK : fmi2Error;
}

EXPORT fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[],
                                        size_t size)
{
    Instance *in = (Instance *)c;
    PyGILState_STATE gil;
    State *state;
    PyObject *bytes = NULL;
    fmi2Status status = fmi2Error;
    if (in == NULL) return fmi2Error;
    gil = enter_python();
    state = as_state(in, "fmi2SerializeFMUstate", FMUstate);
    if (state != NULL) bytes = serialized(in, "fmi2SerializeFMUstate", state);
    if (bytes != NULL) {
        size_t n = (size_t)PyBytes_GET_SIZE(bytes);
        if (serializedState == NULL || size < n) {
            logf_(in, fmi2Error, "fmi2SerializeFMUstate: the buffer (%zu bytes%s) is smaller than the state (%zu bytes)",
                  size, serializedState == NULL ? ", NULL" : "", n);
        } else {
            memcpy(serializedState, PyBytes_AS_STRING(bytes), n);
            status = fmi2OK;
        }
    }
    leave_python(gil);
    return status;
}

EXPORT fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                          fmi2FMUstate *FMUstate)
{
    Instance *in = (Instance *)c;
    PyGILState_STATE gil;
    PyObject *bytes, *value = NULL;
    fmi2Status status;
    if (in == NULL) return fmi2Error;
    if (FMUstate == NULL || (serializedState == NULL && size > 0)) {
        logf_(in, fmi2Error, "fmi2DeSerializeFMUstate: %s is NULL",
              FMUstate == NULL ? "the FMUstate pointer" : "the serialised state");
        return fmi2Error;
    }
    gil = enter_python();
    bytes = PyBytes_FromStringAndSize(serializedState, (Py_ssize_t)size);
    /* A parcosim slave reads the bytes against the instance (model, GUID, configuration, its own
     * state's layout); any other pythonfmu slave as pythonfmu does, on its class. */
    if (bytes != NULL)
        value = PyObject_HasAttr(in->slave, s_deserialize) ? PyObject_CallMethodOneArg(in->slave, s_deserialize, bytes)
                                                           : PyObject_CallMethodOneArg(in->cls, s_from_bytes, bytes);
    Py_XDECREF(bytes);
    if (value == NULL) status = failed(in, "fmi2DeSerializeFMUstate");
    else { drain_log(in); status = store_state(in, "fmi2DeSerializeFMUstate", FMUstate, value); }
    leave_python(gil);
    return status;
}
