/* The frames' triple buffer (frames.c): the consumer takes the newest frame published, never one
 * twice and never one the producer is still writing; the log hands over every published frame's
 * facts in order until AO_FRAMES_LOG wait unread; and under contention, a producer publishing as
 * fast as it can against a consumer taking as fast as it can, every frame taken is whole and newer
 * than the last (the threads suite runs this under ThreadSanitizer too). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <pthread.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdlib.h>

#include "frames.h"
#include "unit_main.h"

/* Fills the back frame, width x height pixels, with every value `serial`, and publishes it. */
static void publish(struct ao_frames *fs, uint32_t serial, int width, int height)
{
    struct ao_frame *f = ao_frames_back(fs, width, height, 1);
    assert_non_null(f);
    for (size_t k = 0; k < 3 * (size_t)width * (size_t)height; k++)
        f->rgb[k] = (float)serial;
    f->tile_error[0] = (float)serial;
    f->info = (struct ao_frame_info){.pass = serial};
    ao_frames_publish(fs);
}

/* The frame is whole: every value is its serial. */
static void assert_whole(const struct ao_frame *f)
{
    for (size_t k = 0; k < 3 * (size_t)f->width * (size_t)f->height; k++)
        if (f->rgb[k] != (float)f->info.pass)
            fail_msg("frame %u holds %g at %zu: torn", f->info.pass, f->rgb[k], k);
    assert_true(f->tile_error[0] == (float)f->info.pass);
}

/* Takes the back frame, width x 3, for an update in place, stamps it `stamp` and publishes it;
 * returns the stamp it had. */
static uint64_t restamp(struct ao_frames *fs, int width, uint64_t stamp)
{
    uint64_t kept = 99;
    assert_non_null(ao_frames_back_stamped(fs, width, 3, 1, &kept));
    ao_frames_stamp_back(fs, stamp);
    ao_frames_publish(fs);
    return kept;
}

/* A producer that updates frames in place learns what each back frame's pixels hold: the stamp it
 * gave them, until they are filled otherwise (ao_frames_back, or taken for an update that is not
 * stamped) or their size changes (0). With no consumer the producer's frames alternate between
 * two of the three. */
static void test_stamps(void **state)
{
    (void)state;
    struct ao_frames fs;
    ao_frames_init(&fs);
    uint64_t kept;
    assert_int_equal(restamp(&fs, 4, 1), 0);
    assert_int_equal(restamp(&fs, 4, 2), 0);   /* the other of the two, never stamped */
    assert_int_equal(restamp(&fs, 4, 3), 1);
    assert_non_null(ao_frames_back(&fs, 4, 3, 1));   /* the second, filled otherwise */
    ao_frames_publish(&fs);
    assert_int_equal(restamp(&fs, 4, 4), 3);
    assert_int_equal(restamp(&fs, 4, 5), 0);   /* ao_frames_back cleared its stamp */
    assert_non_null(ao_frames_back_stamped(&fs, 4, 3, 1, &kept));   /* an update left unstamped */
    assert_int_equal(kept, 4);
    ao_frames_publish(&fs);
    assert_int_equal(restamp(&fs, 4, 6), 5);
    assert_int_equal(restamp(&fs, 4, 7), 0);
    assert_int_equal(restamp(&fs, 5, 8), 0);   /* the first at another size */
    ao_frames_finish(&fs);
}

/* Nothing before the first publish; then the newest, once; frames in between are skipped. */
static void test_take_newest(void **state)
{
    (void)state;
    struct ao_frames fs;
    ao_frames_init(&fs);
    assert_null(ao_frames_take(&fs));
    publish(&fs, 1, 4, 3);
    publish(&fs, 2, 4, 3);
    const struct ao_frame *f = ao_frames_take(&fs);
    assert_non_null(f);
    assert_int_equal(f->info.pass, 2);
    assert_int_equal(f->width, 4);
    assert_int_equal(f->height, 3);
    assert_whole(f);
    assert_null(ao_frames_take(&fs));
    publish(&fs, 3, 2, 2);   /* another size: the back frame is resized */
    f = ao_frames_take(&fs);
    assert_non_null(f);
    assert_int_equal(f->info.pass, 3);
    assert_int_equal(f->width, 2);
    assert_whole(f);
    /* The frame taken stays as it is while the producer goes on (two more publishes touch only the
     * two other frames). */
    publish(&fs, 4, 2, 2);
    publish(&fs, 5, 2, 2);
    assert_int_equal(f->info.pass, 3);
    assert_whole(f);
    assert_int_equal(ao_frames_take(&fs)->info.pass, 5);
    ao_frames_finish(&fs);
}

/* The log: every frame's facts, oldest first, in as many takes as the consumer likes; while
 * AO_FRAMES_LOG wait unread, newer ones are not logged (the frames themselves still pass). */
static void test_log(void **state)
{
    (void)state;
    struct ao_frames fs;
    ao_frames_init(&fs);
    struct ao_frame_info out[AO_FRAMES_LOG];
    assert_int_equal(ao_frames_take_log(&fs, out, AO_FRAMES_LOG), 0);
    for (uint32_t s = 1; s <= 5; s++)
        publish(&fs, s, 1, 1);
    assert_int_equal(ao_frames_take_log(&fs, out, 2), 2);
    assert_int_equal(out[0].pass, 1);
    assert_int_equal(out[1].pass, 2);
    assert_int_equal(ao_frames_take_log(&fs, out, AO_FRAMES_LOG), 3);
    assert_int_equal(out[2].pass, 5);
    for (uint32_t s = 6; s < 6 + AO_FRAMES_LOG + 10; s++)
        publish(&fs, s, 1, 1);
    assert_int_equal(ao_frames_take_log(&fs, out, AO_FRAMES_LOG), AO_FRAMES_LOG);
    for (int k = 0; k < AO_FRAMES_LOG; k++)
        assert_int_equal(out[k].pass, 6 + k);
    assert_int_equal(ao_frames_take_log(&fs, out, AO_FRAMES_LOG), 0);
    assert_int_equal(ao_frames_take(&fs)->info.pass, 6 + AO_FRAMES_LOG + 9);
    ao_frames_finish(&fs);
}

/* The producer's side of the contention test: FRAMES frames of 16 x 16 pixels (a frame's values
 * take long enough to write that the consumer often takes while one is being written). Every PACE
 * frames it waits until the consumer has taken PACE's share: on a loaded machine the producer
 * could otherwise publish all of them before the consumer runs once, and the test would see no
 * handoff at all. Between waits both run at full speed. */
enum { FRAMES = 100000, PACE = 1000 };

/* The two threads' shared state: the frames and how many the consumer has taken. */
struct contention {
    struct ao_frames frames;
    atomic_size_t taken;
};

static void *produce(void *arg)
{
    struct contention *c = arg;
    for (uint32_t s = 1; s <= FRAMES; s++) {
        publish(&c->frames, s, 16, 16);
        /* A frame was just published, so the consumer, looping until it takes frame FRAMES, always
         * has a new one to take: the wait ends. */
        while (s % PACE == 0 && atomic_load(&c->taken) < s / PACE)
            sched_yield();
    }
    return NULL;
}

/* A producer and a consumer at full speed on two threads: every frame taken is whole and newer
 * than the one before; the log's facts come in order (some left out while it was full); the last
 * frame is taken in the end. */
static void test_handoff_under_contention(void **state)
{
    (void)state;
    struct contention c = {.taken = 0};
    ao_frames_init(&c.frames);
    pthread_t producer;
    assert_int_equal(pthread_create(&producer, NULL, produce, &c), 0);
    uint32_t last = 0, last_logged = 0;
    size_t logged = 0;
    struct ao_frame_info out[64];
    while (last < FRAMES) {
        const struct ao_frame *f = ao_frames_take(&c.frames);
        if (f) {
            assert_true(f->info.pass > last);
            assert_whole(f);
            last = f->info.pass;
            atomic_fetch_add(&c.taken, 1);
        }
        for (int n = ao_frames_take_log(&c.frames, out, 64), k = 0; k < n; k++) {
            assert_true(out[k].pass > last_logged);
            last_logged = out[k].pass;
            logged++;
        }
    }
    assert_int_equal(pthread_join(producer, NULL), 0);
    assert_null(ao_frames_take(&c.frames));
    for (int n; (n = ao_frames_take_log(&c.frames, out, 64)) > 0;)
        for (int k = 0; k < n; k++) {
            assert_true(out[k].pass > last_logged);
            last_logged = out[k].pass;
            logged++;
        }
    size_t taken = atomic_load(&c.taken);
    print_message("%zu of %d frames taken, %zu logged\n", taken, FRAMES, logged);
    assert_true(taken >= FRAMES / PACE);
    assert_true(logged > 0);
    ao_frames_finish(&c.frames);
}

UNIT_TEST_MAIN(cmocka_unit_test(test_take_newest), cmocka_unit_test(test_log), cmocka_unit_test(test_stamps),
               cmocka_unit_test(test_handoff_under_contention))
