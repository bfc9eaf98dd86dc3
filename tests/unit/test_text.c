/* text.c: what a one-line message may quote of user text; the sink that messages go to, by level,
 * routed per thread, from a job's workers to the thread that ran the job; NULL dropping them. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <string.h>

#include "capture.h"
#include "pool.h"
#include "text.h"

static void test_plain_text_is_kept(void **state)
{
    (void)state;
    char out[64];
    assert_string_equal(ao_text_escape("out.png", out, sizeof out), "out.png");
    assert_string_equal(ao_text_escape("", out, sizeof out), "");
    /* UTF-8 names stay readable */
    assert_string_equal(ao_text_escape("bild-\xc3\xa4\xe2\x82\xac.png", out, sizeof out), "bild-\xc3\xa4\xe2\x82\xac.png");
}

static void test_controls_become_escapes(void **state)
{
    (void)state;
    char out[64];
    assert_string_equal(ao_text_escape("a\nb\rc\td", out, sizeof out), "a\\nb\\rc\\td");
    assert_string_equal(ao_text_escape("back\\slash", out, sizeof out), "back\\\\slash");
    assert_string_equal(ao_text_escape("\x1b[31mred\x7f", out, sizeof out), "\\x1b[31mred\\x7f");
    /* U+009B, the one-character CSI, in UTF-8; a lone 0xc2 before other bytes is kept */
    assert_string_equal(ao_text_escape("x\xc2\x9by", out, sizeof out), "x\\xc2\\x9by");
    assert_string_equal(ao_text_escape("\xc2\xa0", out, sizeof out), "\xc2\xa0");
}

/* Cut with "..." where it does not fit, never in the middle of an escape, always NUL-terminated. */
static void test_long_text_is_cut(void **state)
{
    (void)state;
    char out[8];
    assert_string_equal(ao_text_escape("1234567", out, sizeof out), "1234567");
    assert_string_equal(ao_text_escape("12345678", out, sizeof out), "1234...");
    assert_string_equal(ao_text_escape("1\n345678", out, sizeof out), "1\\n3...");
    assert_string_equal(ao_text_escape("123\n", out, sizeof out), "123\\n");
    assert_string_equal(ao_text_escape("12345\n", out, sizeof out), "12345\\n");
    assert_string_equal(ao_text_escape("123456\n", out, sizeof out), "1234...");
    char big[AO_TEXT_SIZE];
    char name[3000];
    memset(name, '\n', sizeof name - 1);
    name[sizeof name - 1] = '\0';
    ao_text_escape(name, big, sizeof big);
    assert_true(strlen(big) < sizeof big);
    assert_null(strchr(big, '\n'));
    assert_string_equal(big + strlen(big) - 5, "\\n...");
}

/* Errors and notes reach the sink with their level, escaped, one line each without a newline. */
static void test_levels(void **state)
{
    (void)state;
    struct capture c;
    capture_begin(&c);
    ao_text_report("%s: line %d", "bad\nname.scene", 3);
    ao_text_note("read as %s", "decoded");
    ao_text_report("x\x1b[2J");
    capture_end(&c, NULL, 0);
    assert_int_equal(c.errors, 2);
    assert_int_equal(c.notes, 1);
    assert_string_equal(c.text, "bad\\nname.scene: line 3\nread as decoded\nx\\x1b[2J\n");
}

/* What a thread of test_routes_per_thread saw. */
struct routed {
    int index;
    struct capture capture;
    const struct ao_text_sink *first_route, *current, *put_back;
};

enum { ROUTED_LINES = 200 };

/* Routes itself to its own capture, reports its lines, and routes back. */
static void *report_own(void *arg)
{
    struct routed *r = arg;
    r->first_route = ao_text_current();
    capture_begin(&r->capture);
    r->current = ao_text_current();
    for (int k = 0; k < ROUTED_LINES; k++)
        ao_text_report("thread %d line %d", r->index, k);
    capture_end(&r->capture, NULL, 0);
    r->put_back = ao_text_current();
    return NULL;
}

/* Four threads reporting at once each receive exactly their own lines, in order; a thread never
 * routed goes to the process's sink, and routing back returns there. */
static void test_routes_per_thread(void **state)
{
    (void)state;
    enum { THREADS = 4 };
    atomic_int process_lines = 0;
    const struct ao_text_sink process = {.write = capture_count, .user = &process_lines};
    ao_text_set_sink(&process);
    static struct routed routed[THREADS];
    pthread_t ids[THREADS];
    for (int t = 0; t < THREADS; t++) {
        routed[t] = (struct routed){.index = t};
        assert_int_equal(pthread_create(&ids[t], NULL, report_own, &routed[t]), 0);
    }
    for (int t = 0; t < THREADS; t++)
        pthread_join(ids[t], NULL);
    for (int t = 0; t < THREADS; t++) {
        char expected[ROUTED_LINES * 32] = "";
        size_t used = 0;
        for (int k = 0; k < ROUTED_LINES; k++)
            used += (size_t)snprintf(expected + used, sizeof expected - used, "thread %d line %d\n", t, k);
        assert_string_equal(routed[t].capture.text, expected);
        assert_int_equal(routed[t].capture.errors, ROUTED_LINES);
        assert_ptr_equal(routed[t].first_route, &process);
        assert_ptr_equal(routed[t].current, &routed[t].capture.sink);
        assert_ptr_equal(routed[t].put_back, &process);
    }
    assert_int_equal(atomic_load(&process_lines), 0);
    ao_text_report("to the process's sink");
    assert_int_equal(atomic_load(&process_lines), 1);
    ao_text_set_sink(NULL);
}

/* The job of test_pool_job_reaches_its_caller: every thread of the team reports one line. */
static void report_from_team(void *user, int self)
{
    (void)self;
    ao_text_report("%s", (const char *)user);
}

/* What a thread running a job on a shared team got. */
struct submitter {
    struct ao_pool *pool;
    const char *line;
    struct capture capture;
};

static void *run_job(void *arg)
{
    struct submitter *s = arg;
    capture_begin(&s->capture);
    ao_pool_run(s->pool, report_from_team, (void *)s->line);
    capture_end(&s->capture, NULL, 0);
    return NULL;
}

/* A job's workers report to the sink of the thread that ran the job (not the team's creator's):
 * two threads take turns on one team of 4, each gets its 4 lines and no other. */
static void test_pool_job_reaches_its_caller(void **state)
{
    (void)state;
    atomic_int process_lines = 0;
    const struct ao_text_sink process = {.write = capture_count, .user = &process_lines};
    ao_text_set_sink(&process);
    struct ao_pool *pool = ao_pool_create(4, NULL);
    assert_non_null(pool);
    static struct submitter submitters[2];
    const char *lines[2] = {"from the first", "from the second"};
    for (int k = 0; k < 2; k++) {
        submitters[k] = (struct submitter){.pool = pool, .line = lines[k]};
        pthread_t id;
        assert_int_equal(pthread_create(&id, NULL, run_job, &submitters[k]), 0);
        pthread_join(id, NULL);
        char expected[200];
        snprintf(expected, sizeof expected, "%s\n%s\n%s\n%s\n", lines[k], lines[k], lines[k], lines[k]);
        assert_string_equal(submitters[k].capture.text, expected);
    }
    /* A job run by an unrouted thread: the process's sink. */
    ao_pool_run(pool, report_from_team, "unrouted");
    assert_int_equal(atomic_load(&process_lines), 4);
    ao_pool_destroy(pool);
    ao_text_set_sink(NULL);
}

/* Without a sink (none installed, or NULL installed), and routed to a sink without write,
 * messages are dropped; ao_text_route(NULL) goes back to the process's sink. */
static void test_null_drops(void **state)
{
    (void)state;
    assert_null(ao_text_current());
    ao_text_report("nowhere");
    atomic_int lines = 0;
    const struct ao_text_sink counting = {.write = capture_count, .user = &lines}, mute = {0};
    ao_text_set_sink(&counting);
    ao_text_note("counted");
    const struct ao_text_sink *before = ao_text_route(&mute);
    assert_null(before);
    ao_text_report("dropped by the route");
    assert_ptr_equal(ao_text_route(NULL), &mute);
    ao_text_report("counted again");
    ao_text_set_sink(NULL);
    ao_text_report("dropped");
    assert_int_equal(atomic_load(&lines), 2);
    assert_null(ao_text_current());
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_plain_text_is_kept),
        cmocka_unit_test(test_controls_become_escapes),
        cmocka_unit_test(test_long_text_is_cut),
        cmocka_unit_test(test_null_drops),
        cmocka_unit_test(test_levels),
        cmocka_unit_test(test_routes_per_thread),
        cmocka_unit_test(test_pool_job_reaches_its_caller),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
