#include "testlib.h"

#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

int test_failures;
int test_checks;
int test_cases;
int test_cases_failed;

void test_fail(const char *file, int line, const char *fmt, ...)
{
    va_list ap;
    test_failures++;
    fprintf(stderr, "%s:%d: ", file, line);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
}

int test_summary(void)
{
    if (test_checks == 0) {
        fprintf(stderr, "no check ran: a test that checks nothing fails\n");
        return 1;
    }
    printf("%d checks; test cases: %d passed, %d failed\n", test_checks,
           test_cases - test_cases_failed, test_cases_failed);
    return test_failures ? 1 : 0;
}

static const char *env_path(const char *var, const char *name)
{
    static char path[4][4096];
    static int slot;
    const char *dir = getenv(var);
    char *out = path[slot++ & 3];
    if (!dir) {
        test_fail(__FILE__, __LINE__, "environment variable %s is not set (run under ctest)",
                  var);
        dir = ".";
    }
    snprintf(out, sizeof path[0], "%s/%s", dir, name);
    return out;
}

const char *test_shared_model(const char *name)
{
    char rel[512];
    snprintf(rel, sizeof rel, "models/%s", name);
    return env_path("MCSG_SHARED_DIR", rel);
}

const char *test_data(const char *name) { return env_path("MCSG_TEST_DATA", name); }

const char *test_tmp(const char *name) { return env_path("MCSG_TMP", name); }

bool test_read_string(const char *text, mcsg_format format, mcsg_mesh *out, mcsg_error *err)
{
    mcsg_status st = mcsg_mesh_read_memory(text, strlen(text), format, "string", NULL, out, err);
    return st == MCSG_OK;
}
