/* Crash-safe storage: a process saving through the Linux port's file store
 * (boards/linux/file_store.c, the co_storage behind 0x1010) is killed with SIGKILL at random
 * moments, 100 times; after each kill the store file must open cleanly and hold, for the node
 * being saved, one whole image - the one it had before or one of those saved since - and for the
 * other node the image it always had. Never a mix, never a corrupt file.
 *
 * A host test of the file store API (fork + SIGKILL), not over vcan: the child saves image after
 * image in a loop, each image's bytes all derived from its sequence number, so a torn write would
 * show as an image whose bytes disagree (or as a CRC failure, which the store reports and turns
 * into "no image"). */
#define _GNU_SOURCE
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "file_store.h"
#include "unity.h"

#define IMAGE_LEN 600u    /* about a drive's persistent prefix */
#define HASH 0x5EED1234u  /* the dictionary's layout hash */
#define SAVER 5u          /* node whose image the child keeps saving */
#define BYSTANDER 7u      /* node whose image must never change */
#define KILLS 100

static char dir[64];
static char path[128];

void setUp(void) {}

void tearDown(void) {}

/* Image number seq: every byte derived from seq, so any mix of two images is visible. */
static void make_image(uint32_t seq, uint8_t *img)
{
    for (uint32_t i = 0; i < IMAGE_LEN; i++) {
        img[i] = (uint8_t)((seq * 131u + i * 7u + (seq >> 8)) ^ (i >> 3));
    }
    memcpy(img, &seq, sizeof seq);
}

/* The sequence number of a whole image, or -1 if its bytes are not one image's. */
static long image_seq(const uint8_t *img)
{
    uint32_t seq;
    memcpy(&seq, img, sizeof seq);
    uint8_t want[IMAGE_LEN];
    make_image(seq, want);
    return memcmp(want, img, IMAGE_LEN) == 0 ? (long)seq : -1L;
}

static bool save(file_store *store, uint8_t node, uint32_t seq)
{
    file_store_slot slot;
    co_storage st = file_store_storage(store, &slot, node, "vf-s15");
    uint8_t img[IMAGE_LEN];
    make_image(seq, img);
    return st.save(st.ctx, HASH, img, IMAGE_LEN);
}

/* Opens the file as a new process would and returns the saver's sequence number (asserting the
 * file is valid, the image whole and the bystander's untouched). */
static long reopen_and_check(uint32_t bystander_seq)
{
    file_store store;
    memset(&store, 0, sizeof store);
    TEST_ASSERT_TRUE(file_store_open(&store, path));
    TEST_ASSERT_TRUE_MESSAGE(store.loaded_ok, "the store file does not open cleanly");
    file_store_slot slot;
    co_storage st = file_store_storage(&store, &slot, SAVER, "vf-s15");
    uint8_t img[IMAGE_LEN];
    TEST_ASSERT_TRUE_MESSAGE(st.load(st.ctx, HASH, 0, img, IMAGE_LEN), "saver's image missing");
    long seq = image_seq(img);
    TEST_ASSERT_TRUE_MESSAGE(seq >= 0, "the saver's image is a mix of two images");
    st = file_store_storage(&store, &slot, BYSTANDER, "vf-s15");
    TEST_ASSERT_TRUE_MESSAGE(st.load(st.ctx, HASH, 0, img, IMAGE_LEN), "bystander's image lost");
    TEST_ASSERT_EQUAL_INT32((long)bystander_seq, image_seq(img));
    file_store_close(&store);
    return seq;
}

static void test_sigkill_during_saves_leaves_the_old_or_the_new_image(void)
{
    snprintf(dir, sizeof dir, "store_kill_XXXXXX");
    TEST_ASSERT_NOT_NULL(mkdtemp(dir));
    snprintf(path, sizeof path, "%s/store.bin", dir);
    /* the starting file: saver at image 1, bystander at image 1000 */
    file_store store;
    memset(&store, 0, sizeof store);
    TEST_ASSERT_TRUE(file_store_open(&store, path));
    TEST_ASSERT_TRUE(save(&store, BYSTANDER, 1000u));
    TEST_ASSERT_TRUE(save(&store, SAVER, 1u));
    /* how long one save takes here, to spread the kills over a few of them */
    struct timespec a, b;
    clock_gettime(CLOCK_MONOTONIC, &a);
    for (uint32_t i = 0; i < 5u; i++) {
        TEST_ASSERT_TRUE(save(&store, SAVER, 2u + i));
    }
    clock_gettime(CLOCK_MONOTONIC, &b);
    file_store_close(&store);
    long per_save_us = ((b.tv_sec - a.tv_sec) * 1000000L + (b.tv_nsec - a.tv_nsec) / 1000L) / 5L;
    if (per_save_us < 20) {
        per_save_us = 20;
    }
    long seq = reopen_and_check(1000u);
    TEST_ASSERT_EQUAL_INT32(6, seq);

    srand(8u);
    int moved = 0;
    int stayed = 0;
    int torn = 0; /* kills that left a half-written "<file>.tmp": the kill hit a save */
    char tmp[160];
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    for (int k = 0; k < KILLS; k++) {
        long start = seq;
        fflush(NULL);
        pid_t pid = fork();
        TEST_ASSERT_TRUE(pid >= 0);
        if (pid == 0) {
            file_store child;
            memset(&child, 0, sizeof child);
            if (!file_store_open(&child, path)) {
                _exit(3);
            }
            for (uint32_t s = (uint32_t)start + 1u;; s++) {
                (void)save(&child, SAVER, s);
            }
        }
        /* anywhere from before the first save to the middle of the eighth */
        long delay = (long)((unsigned long)rand() % (unsigned long)(per_save_us * 8 + 200));
        struct timespec ts = {delay / 1000000L, (delay % 1000000L) * 1000L};
        nanosleep(&ts, NULL);
        TEST_ASSERT_EQUAL_INT(0, kill(pid, SIGKILL));
        int status = 0;
        TEST_ASSERT_EQUAL_INT(pid, waitpid(pid, &status, 0));
        TEST_ASSERT_TRUE_MESSAGE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL,
                                 "the child ended before it was killed");
        seq = reopen_and_check(1000u);
        TEST_ASSERT_TRUE_MESSAGE(seq >= start, "the store went back to an older image");
        if (unlink(tmp) == 0) {
            torn++;
        }
        if (seq == start) {
            stayed++;
        } else {
            moved++;
        }
    }
    printf("store kill: %d kills, %d during a write of the file, %d left the image the file had "
           "before, %d a newer one (a save takes ~%ld us)\n", KILLS, torn, stayed, moved,
           per_save_us);
    /* a fresh process still saves over whatever the kills left (a stale .tmp included) */
    memset(&store, 0, sizeof store);
    TEST_ASSERT_TRUE(file_store_open(&store, path));
    TEST_ASSERT_TRUE(save(&store, SAVER, 99999u));
    file_store_close(&store);
    TEST_ASSERT_EQUAL_INT32(99999, reopen_and_check(1000u));
    (void)unlink(tmp);
    (void)unlink(path);
    snprintf(tmp, sizeof tmp, "%s.lock", path); /* the store's lock file (file_store.h) */
    (void)unlink(tmp);
    (void)rmdir(dir);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_sigkill_during_saves_leaves_the_old_or_the_new_image);
    return UNITY_END();
}
