/* The part of libcosim's C API (libcosimc 0.11, shipped as libcosimc.so in the libcosimpy
 * wheel) that host.c calls, declared from the public documentation of include/cosim.h in
 * github.com/open-simulation-platform/libcosimc: the wheel ships the library, not its header.
 * Times and durations are integer nanoseconds; functions return 0 (or an index, or a
 * pointer) on success and -1 (or NULL) on error, with cosim_last_error_message() saying why.
 */
#ifndef PARCOSIM_COSIM_API_H
#define PARCOSIM_COSIM_API_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef int64_t cosim_time_point;
typedef int64_t cosim_duration;
typedef uint32_t cosim_value_reference;
typedef int cosim_slave_index;

typedef struct cosim_execution_s cosim_execution;
typedef struct cosim_slave_s cosim_slave;
typedef struct cosim_observer_s cosim_observer;

/* The length of the name fields of the two description structs below. */
#define COSIM_NAME_SIZE 1024

typedef enum { COSIM_REAL, COSIM_INTEGER, COSIM_STRING, COSIM_BOOLEAN } cosim_variable_type;

typedef enum { COSIM_EXECUTION_STOPPED, COSIM_EXECUTION_RUNNING, COSIM_EXECUTION_ERROR } cosim_execution_state;

typedef struct {
    cosim_time_point current_time;
    cosim_execution_state state;
    int error_code;
    double total_average_real_time_factor;
    double rolling_average_real_time_factor;
    double real_time_factor_target;
    int is_real_time_simulation;
    int steps_to_monitor;
} cosim_execution_status;

typedef struct {
    char name[COSIM_NAME_SIZE];
    cosim_value_reference reference;
    cosim_variable_type type;
    int causality;
    int variability;
} cosim_variable_description;

typedef struct {
    char name[COSIM_NAME_SIZE];
    cosim_slave_index index;
} cosim_slave_info;

/* Severity levels of cosim_log_set_output_level, lowest first (TRACE = 0 ... FATAL = 5). */
enum { COSIM_LOG_WARNING = 3, COSIM_LOG_ERROR = 4 };

const char *cosim_last_error_message(void);
void cosim_log_set_output_level(int level);

cosim_execution *cosim_execution_create(cosim_time_point start, cosim_duration step);
cosim_execution *cosim_ssp_execution_create(const char *ssp_path, bool start_defined, cosim_time_point start);
int cosim_execution_destroy(cosim_execution *execution);

cosim_slave *cosim_local_slave_create(const char *fmu_path, const char *instance_name);
cosim_slave_index cosim_execution_add_slave(cosim_execution *execution, cosim_slave *slave);
int cosim_execution_connect_real_variables(cosim_execution *execution, cosim_slave_index from,
                                           cosim_value_reference output, cosim_slave_index to,
                                           cosim_value_reference input);
int cosim_execution_set_real_initial_value(cosim_execution *execution, cosim_slave_index slave,
                                           cosim_value_reference vr, double value);

size_t cosim_execution_get_num_slaves(cosim_execution *execution);
int cosim_execution_get_slave_infos(cosim_execution *execution, cosim_slave_info infos[], size_t n);
int cosim_slave_get_num_variables(cosim_execution *execution, cosim_slave_index slave);
int cosim_slave_get_variables(cosim_execution *execution, cosim_slave_index slave,
                              cosim_variable_description variables[], size_t n);

int cosim_execution_step(cosim_execution *execution, size_t steps);
int cosim_execution_get_status(cosim_execution *execution, cosim_execution_status *status);

cosim_observer *cosim_last_value_observer_create(void);
int cosim_execution_add_observer(cosim_execution *execution, cosim_observer *observer);
int cosim_observer_slave_get_real(cosim_observer *observer, cosim_slave_index slave,
                                  const cosim_value_reference vrs[], size_t n, double values[]);
int cosim_observer_destroy(cosim_observer *observer);

#endif
