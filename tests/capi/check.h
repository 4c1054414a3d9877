/* A minimal check harness shared by the C tests of the ABI: counts checks,
 * reports failures with their line, and ends with the "N passed, N failed"
 * line test runners read. */
#ifndef OMIS_TESTS_CHECK_H
#define OMIS_TESTS_CHECK_H

#include <stdio.h>

static int failures = 0;
static int checks = 0;

#define CHECK(cond)                                                                  \
    do {                                                                             \
        ++checks;                                                                    \
        if (!(cond)) {                                                               \
            ++failures;                                                              \
            fprintf(stderr, "%s:%d: CHECK(%s) failed\n", __FILE__, __LINE__, #cond); \
        }                                                                            \
    } while (0)

/* Prints the summary line; returns the process exit code. */
static int check_summary(void) {
    printf("%d passed, %d failed\n", checks - failures, failures);
    return failures ? 1 : 0;
}

#endif
