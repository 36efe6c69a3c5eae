/* hal_latency: the realtime host's period loop in C, to tell the machine's own wake-up
 * latency from the cost of Python.
 *
 *   gcc -O2 -o hal_latency hal_latency.c
 *   ./hal_latency PERIOD_NS SECONDS CPU PRIORITY SPIN_US KEEP_AWAKE
 *
 * Like hal/rtapi_app.py: pinned to CPU, SCHED_FIFO at PRIORITY (0: normal scheduling),
 * memory locked, sleep to absolute deadlines on CLOCK_MONOTONIC (waking SPIN_US early and
 * busy-waiting to the deadline), /dev/cpu_dma_latency held at 0 when KEEP_AWAKE is 1.
 * Prints one line per period that ran: its deadline (a whole multiple of the period on
 * CLOCK_MONOTONIC, as in the host) and how late it started, in ns. After an overrun the
 * missed deadlines are skipped, as the host does; the gaps tell which.
 * hal_bench.py compiles and runs it; it is not part of the controller.
 */
#define _GNU_SOURCE
#include <fcntl.h>
#include <sched.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/mman.h>
#include <time.h>
#include <unistd.h>

static int64_t now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

int main(int argc, char **argv)
{
    if (argc != 7) {
        fprintf(stderr, "usage: %s PERIOD_NS SECONDS CPU PRIORITY SPIN_US KEEP_AWAKE\n", argv[0]);
        return 2;
    }
    int64_t period = atoll(argv[1]);
    int64_t count = (int64_t)(atof(argv[2]) * 1e9 / period);
    int cpu = atoi(argv[3]);
    int priority = atoi(argv[4]);
    int64_t spin = atoll(argv[5]) * 1000;
    int is_kept_awake = atoi(argv[6]);

    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(cpu, &set);
    if (sched_setaffinity(0, sizeof set, &set) != 0)
        perror("sched_setaffinity");
    if (priority > 0) {
        struct sched_param param = {.sched_priority = priority};
        if (sched_setscheduler(0, SCHED_FIFO, &param) != 0)
            perror("sched_setscheduler");
    }
    if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0)
        perror("mlockall");
    if (is_kept_awake) {
        int32_t zero = 0;
        int fd = open("/dev/cpu_dma_latency", O_WRONLY);
        if (fd < 0 || write(fd, &zero, sizeof zero) != sizeof zero)
            perror("/dev/cpu_dma_latency");
        /* the file stays open until the process exits */
    }
    int64_t *deadlines = calloc((size_t)count, sizeof *deadlines);
    int64_t *lateness = calloc((size_t)count, sizeof *lateness);
    if (!deadlines || !lateness)
        return 1;

    int64_t deadline = (now_ns() / period + 1) * period;
    for (int64_t i = 0; i < count; i++) {
        int64_t wake = deadline - spin;
        struct timespec ts = {.tv_sec = wake / 1000000000, .tv_nsec = wake % 1000000000};
        while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) != 0) {
        }
        int64_t start = now_ns();
        while (start < deadline)
            start = now_ns();
        deadlines[i] = deadline;
        lateness[i] = start - deadline;
        deadline += period;
        int64_t end = now_ns();
        if (end > deadline)
            deadline += ((end - deadline) / period + 1) * period;
    }
    for (int64_t i = 0; i < count; i++)
        printf("%lld %lld\n", (long long)deadlines[i], (long long)lateness[i]);
    return 0;
}
