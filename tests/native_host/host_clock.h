/* What the C hosts of tests/native_host measure with: a clock's reading in seconds and the
 * process's thread count.  Header-only: each host is one C file compiled alone. */
#ifndef PARCOSIM_HOST_CLOCK_H
#define PARCOSIM_HOST_CLOCK_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* CLOCK_PROCESS_CPUTIME_ID (all threads), CLOCK_THREAD_CPUTIME_ID (the caller) or
 * CLOCK_MONOTONIC (wall), in seconds. */
static inline double clock_seconds(clockid_t id)
{
    struct timespec t;
    clock_gettime(id, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* The process's threads now ("Threads:" of /proc/self/status), -1 when unreadable. */
static inline long thread_count(void)
{
    FILE *status = fopen("/proc/self/status", "r");
    char line[512];
    long threads = -1;
    while (status && fgets(line, sizeof line, status))
        if (!strncmp(line, "Threads:", 8))
            threads = strtol(line + 8, NULL, 10);
    if (status)
        fclose(status);
    return threads;
}

#endif
