/* A minimal check harness shared by the C tests of the ABI: counts checks,
 * reports failures with their line, checks the error a call left, and ends
 * with the "N passed, N failed" line test runners read. */
#ifndef OMIS_TESTS_CHECK_H
#define OMIS_TESTS_CHECK_H

#include <stdio.h>
#include <string.h>

#include "omis/omis.h"

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

/* Takes the thread's pending error: true when it is `expected` and its message
 * mentions `word` (NULL: the message is not checked). */
static inline int error_is(OMISError expected, const char* word) {
    const char* message = NULL;
    const OMISError code = omisGetError(&message);
    if (code != expected) {
        fprintf(stderr, "  expected error %d, got %d (%s)\n", (int)expected, (int)code,
                message ? message : "no message");
        return 0;
    }
    if (word && (!message || !strstr(message, word))) {
        fprintf(stderr, "  message '%s' does not mention '%s'\n", message ? message : "",
                word);
        return 0;
    }
    return 1;
}

/* Prints the summary line; returns the process exit code. */
static int check_summary(void) {
    printf("%d passed, %d failed\n", checks - failures, failures);
    return failures ? 1 : 0;
}

#endif
