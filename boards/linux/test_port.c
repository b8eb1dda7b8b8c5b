/* Checks of the Linux port that need no kernel CAN: the file store (atomic writes, corrupt files,
 * several nodes in one file), the SocketCAN transmit path under EAGAIN and ENOBUFS (through a
 * socketpair carrying struct can_frame, with injected errors), frame and error-frame decoding,
 * receive filter IDs, the event loop (stdin lines, signals, no busy loop), and the EtherCAT line's
 * frame path (through a datagram socketpair standing in for the raw Ethernet socket). */
#define _GNU_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include "canopen/node.h"
#include "ecat_port.h"
#include "file_store.h"
#include "loop.h"
#include "od_test.h"
#include "sim.h"
#include "socketcan.h"
#include "unity.h"

static char dir[256];
static char path[300];

void setUp(void)
{
    snprintf(dir, sizeof dir, "/tmp/test_linux_port.XXXXXX");
    TEST_ASSERT_NOT_NULL(mkdtemp(dir));
    snprintf(path, sizeof path, "%s/store.bin", dir);
}

void tearDown(void)
{
    char cmd[300];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    TEST_ASSERT_EQUAL_INT(0, system(cmd));
}

static bool file_exists(const char *p)
{
    struct stat st;
    return stat(p, &st) == 0;
}

/* --- file store -------------------------------------------------------------------------------- */

static void test_store_missing_file_is_empty(void)
{
    file_store fs;
    file_store_slot slot;
    TEST_ASSERT_TRUE(file_store_open(&fs, path));
    co_storage st = file_store_storage(&fs, &slot, 5, "vf-s15");
    uint8_t buf[4] = {9, 9, 9, 9};
    TEST_ASSERT_FALSE(st.load(st.ctx, 0x1234u, 0, buf, 4));
    TEST_ASSERT_EQUAL_UINT8(9, buf[0]); /* untouched */
    TEST_ASSERT_FALSE(file_exists(path));
    file_store_close(&fs);
}

static void test_store_save_then_reload_in_new_process(void)
{
    file_store fs;
    file_store_slot slot;
    TEST_ASSERT_TRUE(file_store_open(&fs, path));
    co_storage st = file_store_storage(&fs, &slot, 5, "vf-s15");
    const uint8_t image[5] = {1, 2, 3, 4, 5};
    TEST_ASSERT_TRUE(st.save(st.ctx, 0xCAFEu, image, 5));
    file_store_close(&fs);

    char tmp[320];
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    TEST_ASSERT_FALSE(file_exists(tmp)); /* renamed away */

    TEST_ASSERT_TRUE(file_store_open(&fs, path)); /* "restart" */
    TEST_ASSERT_TRUE(fs.loaded_ok);
    st = file_store_storage(&fs, &slot, 5, "vf-s15");
    uint8_t buf[5] = {0};
    TEST_ASSERT_TRUE(st.load(st.ctx, 0xCAFEu, 0, buf, 5));
    TEST_ASSERT_EQUAL_UINT8_ARRAY(image, buf, 5);
    uint8_t part[2] = {0};
    TEST_ASSERT_TRUE(st.load(st.ctx, 0xCAFEu, 0, part, 2)); /* the communication prefix */
    TEST_ASSERT_EQUAL_UINT8(1, part[0]);
    uint8_t big[6] = {0};
    TEST_ASSERT_FALSE(st.load(st.ctx, 0xCAFEu, 0, big, 6)); /* longer than stored */
    TEST_ASSERT_FALSE(st.load(st.ctx, 0xBEEFu, 0, buf, 5)); /* another layout: defaults */
    file_store_close(&fs);
}

static void test_store_several_nodes_in_one_file(void)
{
    file_store fs;
    file_store_slot a, b;
    TEST_ASSERT_TRUE(file_store_open(&fs, path));
    co_storage sa = file_store_storage(&fs, &a, 5, "vf-s15");
    co_storage sb = file_store_storage(&fs, &b, 6, "benshaw-rsi");
    const uint8_t ia[3] = {0xA1, 0xA2, 0xA3};
    const uint8_t ib[7] = {0xB1, 0xB2, 0xB3, 0xB4, 0xB5, 0xB6, 0xB7};
    TEST_ASSERT_TRUE(sa.save(sa.ctx, 1u, ia, 3));
    TEST_ASSERT_TRUE(sb.save(sb.ctx, 2u, ib, 7));
    const uint8_t ia2[3] = {0xC1, 0xC2, 0xC3};
    TEST_ASSERT_TRUE(sa.save(sa.ctx, 1u, ia2, 3)); /* replaces node 5 only */
    file_store_close(&fs);

    TEST_ASSERT_TRUE(file_store_open(&fs, path));
    TEST_ASSERT_EQUAL_UINT32(2, fs.record_count);
    sa = file_store_storage(&fs, &a, 5, "vf-s15");
    sb = file_store_storage(&fs, &b, 6, "benshaw-rsi");
    uint8_t buf[7];
    TEST_ASSERT_TRUE(sa.load(sa.ctx, 1u, 0, buf, 3));
    TEST_ASSERT_EQUAL_UINT8_ARRAY(ia2, buf, 3);
    TEST_ASSERT_TRUE(sb.load(sb.ctx, 2u, 0, buf, 7));
    TEST_ASSERT_EQUAL_UINT8_ARRAY(ib, buf, 7);
    /* Node 6 restarted as another drive: its record does not apply. */
    file_store_slot c;
    co_storage sc = file_store_storage(&fs, &c, 6, "vf-s15");
    TEST_ASSERT_FALSE(sc.load(sc.ctx, 2u, 0, buf, 7));
    /* Erase (0x1011) forgets node 5 only. */
    TEST_ASSERT_TRUE(sa.erase(sa.ctx));
    TEST_ASSERT_FALSE(sa.load(sa.ctx, 1u, 0, buf, 3));
    file_store_close(&fs);
    TEST_ASSERT_TRUE(file_store_open(&fs, path));
    TEST_ASSERT_EQUAL_UINT32(1, fs.record_count);
    TEST_ASSERT_EQUAL_UINT8(6, fs.records[0].node_id);
    file_store_close(&fs);
}

static void corrupt_byte(long offset)
{
    FILE *f = fopen(path, "r+b");
    TEST_ASSERT_NOT_NULL(f);
    TEST_ASSERT_EQUAL_INT(0, fseek(f, offset, offset < 0 ? SEEK_END : SEEK_SET));
    int ch = fgetc(f);
    TEST_ASSERT_EQUAL_INT(0, fseek(f, -1, SEEK_CUR));
    fputc(ch ^ 0x5A, f);
    fclose(f);
}

static void save_one(uint8_t node, const char *drive)
{
    file_store fs;
    file_store_slot s;
    TEST_ASSERT_TRUE(file_store_open(&fs, path));
    co_storage st = file_store_storage(&fs, &s, node, drive);
    const uint8_t image[16] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16};
    TEST_ASSERT_TRUE(st.save(st.ctx, 7u, image, 16));
    file_store_close(&fs);
}

static void expect_defaults_after_open(void)
{
    file_store fs;
    file_store_slot s;
    TEST_ASSERT_TRUE(file_store_open(&fs, path));
    TEST_ASSERT_FALSE(fs.loaded_ok);
    TEST_ASSERT_EQUAL_UINT32(0, fs.record_count);
    co_storage st = file_store_storage(&fs, &s, 5, "vf-s15");
    uint8_t buf[16] = {0};
    TEST_ASSERT_FALSE(st.load(st.ctx, 7u, 0, buf, 16));
    /* The next store writes a good file again. */
    TEST_ASSERT_TRUE(st.save(st.ctx, 7u, buf, 16));
    file_store_close(&fs);
    TEST_ASSERT_TRUE(file_store_open(&fs, path));
    TEST_ASSERT_TRUE(fs.loaded_ok);
    file_store_close(&fs);
}

static void test_store_corrupt_data_gives_defaults(void)
{
    save_one(5, "vf-s15");
    corrupt_byte(70); /* inside the record data */
    expect_defaults_after_open();
}

static void test_store_corrupt_magic_gives_defaults(void)
{
    save_one(5, "vf-s15");
    corrupt_byte(0);
    expect_defaults_after_open();
}

static void test_store_truncated_file_gives_defaults(void)
{
    save_one(5, "vf-s15");
    struct stat st;
    TEST_ASSERT_EQUAL_INT(0, stat(path, &st));
    for (off_t len = 0; len < st.st_size; len += 7) {
        save_one(5, "vf-s15");
        TEST_ASSERT_EQUAL_INT(0, truncate(path, len));
        expect_defaults_after_open();
    }
}

static void test_store_crash_before_rename_keeps_old_values(void)
{
    save_one(5, "vf-s15");
    /* A crash mid-save leaves a half-written temporary file next to the intact old one. */
    char tmp[320];
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    FILE *f = fopen(tmp, "wb");
    TEST_ASSERT_NOT_NULL(f);
    fputs("CODSTOR1 half", f);
    fclose(f);
    file_store fs;
    file_store_slot s;
    TEST_ASSERT_TRUE(file_store_open(&fs, path));
    TEST_ASSERT_TRUE(fs.loaded_ok);
    co_storage st = file_store_storage(&fs, &s, 5, "vf-s15");
    uint8_t buf[16];
    TEST_ASSERT_TRUE(st.load(st.ctx, 7u, 0, buf, 16));
    TEST_ASSERT_EQUAL_UINT8(16, buf[15]);
    file_store_close(&fs);
}

static void test_store_failed_save_keeps_old_values(void)
{
    save_one(5, "vf-s15");
    file_store fs;
    file_store_slot s;
    TEST_ASSERT_TRUE(file_store_open(&fs, path));
    co_storage st = file_store_storage(&fs, &s, 5, "vf-s15");
    /* Make the temporary file impossible to create: a directory in its place. */
    char tmp[320];
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    TEST_ASSERT_EQUAL_INT(0, mkdir(tmp, 0700));
    const uint8_t other[16] = {0};
    TEST_ASSERT_FALSE(st.save(st.ctx, 7u, other, 16));
    uint8_t buf[16];
    TEST_ASSERT_TRUE(st.load(st.ctx, 7u, 0, buf, 16)); /* memory keeps the old image */
    TEST_ASSERT_EQUAL_UINT8(16, buf[15]);
    file_store_close(&fs);
    TEST_ASSERT_EQUAL_INT(0, rmdir(tmp));
    TEST_ASSERT_TRUE(file_store_open(&fs, path)); /* and so does the file */
    st = file_store_storage(&fs, &s, 5, "vf-s15");
    TEST_ASSERT_TRUE(st.load(st.ctx, 7u, 0, buf, 16));
    TEST_ASSERT_EQUAL_UINT8(16, buf[15]);
    file_store_close(&fs);
}

/* What the calls between capture_begin(fd) and capture_end() wrote to fd (stdout or stderr). */
static int captured_fd = -1;
static int saved_fd = -1;
static char capture_file[320];
static char captured[65536];

static void capture_begin(int fd)
{
    snprintf(capture_file, sizeof capture_file, "%s/captured.txt", dir);
    fflush(NULL);
    captured_fd = fd;
    saved_fd = dup(fd);
    TEST_ASSERT_TRUE(saved_fd >= 0);
    int file = open(capture_file, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    TEST_ASSERT_TRUE(file >= 0);
    TEST_ASSERT_EQUAL_INT(fd, dup2(file, fd));
    close(file);
}

static const char *capture_end(void)
{
    fflush(NULL);
    TEST_ASSERT_EQUAL_INT(captured_fd, dup2(saved_fd, captured_fd));
    close(saved_fd);
    saved_fd = -1;
    FILE *f = fopen(capture_file, "r");
    TEST_ASSERT_NOT_NULL(f);
    size_t n = fread(captured, 1, sizeof captured - 1u, f);
    fclose(f);
    captured[n] = '\0';
    return captured;
}

static void stderr_begin(void)
{
    capture_begin(STDERR_FILENO);
}

static const char *stderr_end(void)
{
    return capture_end();
}

static unsigned count_lines_with(const char *text, const char *needle)
{
    unsigned count = 0;
    for (const char *p = strstr(text, needle); p != NULL; p = strstr(p + 1, needle)) {
        count++;
    }
    return count;
}

#define TEST_ASSERT_CONTAINS(needle, haystack)                                                 \
    TEST_ASSERT_NOT_NULL_MESSAGE(strstr((haystack), (needle)), (haystack))

/* Two processes on one store file: each would rewrite the whole file from its own memory, and
 * the later save would silently drop the earlier one's acknowledged image. The second process
 * is refused at start-up instead, and may start once the first has closed the store. */
static void test_store_second_process_on_one_file_is_refused(void)
{
    file_store a;
    file_store_slot sa;
    TEST_ASSERT_TRUE(file_store_open(&a, path));
    co_storage st = file_store_storage(&a, &sa, 5, "vf-s15");
    const uint8_t img111[2] = {111, 0};
    TEST_ASSERT_TRUE(st.save(st.ctx, 7u, img111, 2));

    /* another process */
    fflush(NULL);
    pid_t pid = fork();
    TEST_ASSERT_TRUE(pid >= 0);
    if (pid == 0) {
        file_store b;
        int devnull = open("/dev/null", O_WRONLY);
        dup2(devnull, STDERR_FILENO);
        _exit(file_store_open(&b, path) ? 1 : 0);
    }
    int status = 0;
    TEST_ASSERT_EQUAL_INT(pid, waitpid(pid, &status, 0));
    TEST_ASSERT_TRUE_MESSAGE(WIFEXITED(status) && WEXITSTATUS(status) == 0,
                             "a second process opened a store file in use");

    /* a second open in this process (another open file description) is refused the same way,
     * and says why and who holds it */
    file_store b;
    stderr_begin();
    bool opened = file_store_open(&b, path);
    const char *err = stderr_end();
    TEST_ASSERT_FALSE(opened);
    TEST_ASSERT_CONTAINS("in use by another process", err);
    char pid_text[32];
    snprintf(pid_text, sizeof pid_text, "(process %ld)", (long)getpid());
    TEST_ASSERT_CONTAINS(pid_text, err);
    TEST_ASSERT_CONTAINS(".lock", err);

    /* the first process's save is intact; once it is gone, the file can be taken */
    file_store_close(&a);
    TEST_ASSERT_TRUE(file_store_open(&b, path));
    st = file_store_storage(&b, &sa, 5, "vf-s15");
    uint8_t buf[2] = {0, 0};
    TEST_ASSERT_TRUE(st.load(st.ctx, 7u, 0, buf, 2));
    TEST_ASSERT_EQUAL_UINT8(111, buf[0]);
    file_store_close(&b);
}

/* Only a regular file (or no file) can be a store: anything else is refused at once with what
 * it is, without opening it (a FIFO would block the start-up for ever) and without creating
 * a lock file beside it. */
static void expect_refused(const char *store_path, const char *what)
{
    char lock[340];
    snprintf(lock, sizeof lock, "%s.lock", store_path);
    file_store fs;
    stderr_begin();
    alarm(10); /* a blocking open would end the test here */
    bool opened = file_store_open(&fs, store_path);
    alarm(0);
    const char *err = stderr_end();
    TEST_ASSERT_FALSE_MESSAGE(opened, what);
    TEST_ASSERT_CONTAINS(what, err);
    TEST_ASSERT_CONTAINS(store_path, err);
    TEST_ASSERT_FALSE(file_exists(lock));
}

static void test_store_refuses_what_is_not_a_regular_file(void)
{
    char p[320];
    snprintf(p, sizeof p, "%s/fifo", dir);
    TEST_ASSERT_EQUAL_INT(0, mkfifo(p, 0600));
    expect_refused(p, "is a FIFO (named pipe), not a regular file");

    snprintf(p, sizeof p, "%s/directory", dir);
    TEST_ASSERT_EQUAL_INT(0, mkdir(p, 0700));
    expect_refused(p, "is a directory, not a regular file");

    snprintf(p, sizeof p, "%s/zero", dir);
    TEST_ASSERT_EQUAL_INT(0, symlink("/dev/zero", p));
    expect_refused(p, "is a character device, not a regular file");

    snprintf(p, sizeof p, "%s/socket", dir);
    int s = socket(AF_UNIX, SOCK_STREAM, 0);
    struct sockaddr_un sun;
    memset(&sun, 0, sizeof sun);
    sun.sun_family = AF_UNIX;
    TEST_ASSERT_TRUE(strlen(p) < sizeof sun.sun_path);
    memcpy(sun.sun_path, p, strlen(p) + 1u);
    TEST_ASSERT_EQUAL_INT(0, bind(s, (struct sockaddr *)&sun, sizeof sun));
    expect_refused(p, "is a socket, not a regular file");
    close(s);
}

static void test_store_refuses_a_file_larger_than_any_store(void)
{
    /* 2 GiB, sparse: costs no disk */
    int fd = open(path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    TEST_ASSERT_TRUE(fd >= 0);
    TEST_ASSERT_EQUAL_INT(0, ftruncate(fd, (off_t)1 << 31));
    close(fd);
    char what[128];
    snprintf(what, sizeof what, "is 2147483648 bytes, larger than any store file can be (at most "
             "%lu bytes)", (unsigned long)FILE_STORE_MAX_FILE);
    expect_refused(path, what);
    /* the largest possible store file is still read (and found damaged, not refused) */
    TEST_ASSERT_EQUAL_INT(0, truncate(path, (off_t)FILE_STORE_MAX_FILE));
    file_store fs;
    stderr_begin();
    bool opened = file_store_open(&fs, path);
    const char *err = stderr_end();
    TEST_ASSERT_TRUE(opened);
    TEST_ASSERT_FALSE(fs.loaded_ok);
    TEST_ASSERT_CONTAINS("ignored: not a canopen-drive store file", err);
    file_store_close(&fs);
}

static void test_store_crc32_check_value(void)
{
    const uint8_t s[9] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
    TEST_ASSERT_EQUAL_HEX32(0xCBF43926u, file_store_crc32(0, s, 9));
}

/* --- SocketCAN frames over a socketpair --------------------------------------------------------- */

static int pair[2];
static sc_port port;

static void open_pair(void)
{
    TEST_ASSERT_EQUAL_INT(0, socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK, 0, pair));
    sc_attach(&port, pair[0], "pair");
}

static void close_pair(void)
{
    close(pair[0]);
    close(pair[1]);
}

static void test_recv_decodes_frames_and_error_frames(void)
{
    open_pair();
    struct can_frame cf;
    memset(&cf, 0, sizeof cf);
    cf.can_id = 0x605;
    cf.can_dlc = 8;
    cf.data[0] = 0x40;
    cf.data[7] = 0x77;
    TEST_ASSERT_EQUAL_INT(sizeof cf, write(pair[1], &cf, sizeof cf));
    memset(&cf, 0, sizeof cf);
    cf.can_id = 0x705 | CAN_RTR_FLAG;
    cf.can_dlc = 1;
    TEST_ASSERT_EQUAL_INT(sizeof cf, write(pair[1], &cf, sizeof cf));
    cf.can_id = 0x12345 | CAN_EFF_FLAG;
    TEST_ASSERT_EQUAL_INT(sizeof cf, write(pair[1], &cf, sizeof cf));
    memset(&cf, 0, sizeof cf);
    cf.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF | CAN_ERR_CRTL | CAN_ERR_RESTARTED;
    cf.can_dlc = CAN_ERR_DLC;
    cf.data[1] = CAN_ERR_CRTL_TX_PASSIVE;
    TEST_ASSERT_EQUAL_INT(sizeof cf, write(pair[1], &cf, sizeof cf));

    co_frame f;
    sc_bus_event ev;
    TEST_ASSERT_EQUAL_INT(SC_RECV_FRAME, sc_recv(&port, &f, &ev));
    TEST_ASSERT_EQUAL_HEX16(0x605, f.id);
    TEST_ASSERT_EQUAL_UINT8(8, f.dlc);
    TEST_ASSERT_EQUAL_UINT8(0, f.flags);
    TEST_ASSERT_EQUAL_HEX8(0x77, f.data[7]);
    TEST_ASSERT_EQUAL_INT(SC_RECV_FRAME, sc_recv(&port, &f, &ev));
    TEST_ASSERT_EQUAL_HEX16(0x705, f.id);
    TEST_ASSERT_EQUAL_UINT8(CO_FRAME_RTR, f.flags);
    TEST_ASSERT_EQUAL_UINT8(1, f.dlc);
    TEST_ASSERT_EQUAL_INT(SC_RECV_SKIPPED, sc_recv(&port, &f, &ev)); /* extended frame */
    TEST_ASSERT_EQUAL_INT(SC_RECV_EVENT, sc_recv(&port, &f, &ev));
    TEST_ASSERT_EQUAL_INT(SC_BUS_OFF, ev);
    TEST_ASSERT_EQUAL_INT(SC_RECV_EVENT, sc_recv(&port, &f, &ev));
    TEST_ASSERT_EQUAL_INT(SC_BUS_ERROR_PASSIVE, ev);
    TEST_ASSERT_EQUAL_INT(SC_RECV_EVENT, sc_recv(&port, &f, &ev));
    TEST_ASSERT_EQUAL_INT(SC_BUS_RESTARTED, ev);
    TEST_ASSERT_EQUAL_INT(SC_RECV_NONE, sc_recv(&port, &f, &ev));
    TEST_ASSERT_EQUAL_UINT32(1, port.stats.rx_error_frames);
    close_pair();
}

static int fake_errno_left; /* sends still to refuse */
static int fake_errno;
static ssize_t fake_send(int fd, const void *buf, size_t len, int flags)
{
    if (fake_errno_left > 0) {
        fake_errno_left--;
        errno = fake_errno;
        return -1;
    }
    return send(fd, buf, len, flags);
}

/* A node on the test dictionary sending through the port. */
static co_node node;
static uint8_t values[CO_OD_TEST_VALUE_SIZE + 8u] __attribute__((aligned(8)));

static void start_node(void)
{
    co_node_config cfg = co_node_default_config();
    cfg.od = &co_od_test;
    cfg.values = values;
    cfg.node_id = 5;
    cfg.driver.send = sc_send;
    cfg.driver.ctx = &port;
    TEST_ASSERT_TRUE(co_node_init(&node, &cfg));
    co_node_start(&node, loop_now());
}

static void expect_peer_frame(uint16_t id, uint8_t dlc, uint8_t b0)
{
    struct can_frame cf;
    TEST_ASSERT_EQUAL_INT(sizeof cf, read(pair[1], &cf, sizeof cf));
    TEST_ASSERT_EQUAL_HEX32(id, cf.can_id);
    TEST_ASSERT_EQUAL_UINT8(dlc, cf.can_dlc);
    TEST_ASSERT_EQUAL_HEX8(b0, cf.data[0]);
}

/* Sends n numbered frames through the core; returns how many the core accepted. */
static unsigned send_numbered(unsigned first, unsigned n)
{
    unsigned ok = 0;
    for (unsigned i = first; i < first + n; i++) {
        co_frame f = {0x181, 2, 0, {(uint8_t)i, (uint8_t)(i >> 8)}};
        ok += co_node_send(&node, &f) ? 1u : 0u;
    }
    return ok;
}

/* Member of a loop that drains the peer end slowly and stops once `want` frames arrived. */
typedef struct drain {
    unsigned got;
    unsigned want;
    unsigned per_tick;
    bool in_order;
    loop *lp;
} drain;

static uint64_t drain_process(void *ctx, uint64_t now)
{
    drain *d = ctx;
    for (unsigned k = 0; k < d->per_tick; k++) {
        struct can_frame cf;
        if (read(pair[1], &cf, sizeof cf) != (ssize_t)sizeof cf) {
            break;
        }
        if (cf.can_id != 0x181) {
            continue; /* boot-up */
        }
        unsigned seq = cf.data[0] | (cf.data[1] << 8);
        d->in_order = d->in_order && seq == d->got;
        d->got++;
    }
    if (d->got >= d->want) {
        loop_stop(d->lp);
    }
    return now + 2000u; /* drain a little every 2 ms */
}

static void drain_rx(void *ctx, const co_frame *f, uint64_t now)
{
    (void)ctx;
    (void)f;
    (void)now;
}

static void drain_tx_ready(void *ctx, uint64_t now)
{
    (void)ctx;
    (void)now;
    co_node_tx_ready(&node);
}

static void run_drain(unsigned want, unsigned per_tick)
{
    loop lp;
    TEST_ASSERT_EQUAL_INT(0, loop_init(&lp));
    drain d = {0, want, per_tick, true, &lp};
    loop_member m = {&port, &d, drain_rx, NULL, drain_process, drain_tx_ready, -1, NULL};
    TEST_ASSERT_EQUAL_INT(0, loop_add(&lp, &m));
    alarm(20);
    TEST_ASSERT_EQUAL_INT(0, loop_run(&lp));
    alarm(0);
    loop_close(&lp);
    TEST_ASSERT_EQUAL_UINT(want, d.got);
    TEST_ASSERT_TRUE(d.in_order);
}

static void test_eagain_frames_wait_for_epollout_and_keep_order(void)
{
    open_pair();
    int small = 1; /* the kernel rounds it up to its minimum: a few frames fit */
    TEST_ASSERT_EQUAL_INT(0, setsockopt(pair[0], SOL_SOCKET, SO_SNDBUF, &small, sizeof small));
    start_node();
    expect_peer_frame(0x705, 1, 0x00); /* boot-up */
    /* Fill the socket until the kernel refuses; then the core queues the rest. */
    unsigned sent = 0;
    while (port.tx_state == SC_TX_READY && sent < 10000u) {
        sent += send_numbered(sent, 1);
    }
    TEST_ASSERT_EQUAL_INT(SC_TX_WAIT_WRITABLE, port.tx_state);
    TEST_ASSERT_TRUE(port.stats.tx_eagain >= 1u);
    unsigned queued_ok = send_numbered(sent, CO_TX_QUEUE_LEN - 1u);
    TEST_ASSERT_EQUAL_UINT(CO_TX_QUEUE_LEN - 1u, queued_ok);
    TEST_ASSERT_EQUAL_UINT32(0, node.stats.tx_dropped);
    /* The loop drains 2 frames per 2 ms tick: EPOLLOUT resumes sending until all arrived. */
    run_drain(sent + CO_TX_QUEUE_LEN - 1u, 2);
    TEST_ASSERT_EQUAL_INT(SC_TX_READY, port.tx_state);
    TEST_ASSERT_EQUAL_UINT16(0, node.txq.count);
    close_pair();
}

static void test_enobufs_is_retried_after_a_delay(void)
{
    open_pair();
    port.sys_send = fake_send;
    start_node();
    expect_peer_frame(0x705, 1, 0x00);
    fake_errno = ENOBUFS;
    fake_errno_left = 3;
    TEST_ASSERT_EQUAL_UINT(8, send_numbered(0, 8)); /* all kept by the core */
    TEST_ASSERT_EQUAL_INT(SC_TX_WAIT_RETRY, port.tx_state);
    TEST_ASSERT_EQUAL_UINT32(1, port.stats.tx_enobufs);
    uint64_t now = loop_now();
    uint64_t retry = sc_tx_retry_time(&port, now);
    TEST_ASSERT_TRUE(retry > now && retry <= now + 1000u);
    run_drain(8, 8);
    TEST_ASSERT_EQUAL_UINT32(3, port.stats.tx_enobufs);
    TEST_ASSERT_EQUAL_UINT32(0, node.stats.tx_dropped);
    close_pair();
}

static void test_hold_keeps_frames_in_order_until_released(void)
{
    open_pair();
    start_node();
    expect_peer_frame(0x705, 1, 0x00);
    port.hold = true;
    TEST_ASSERT_EQUAL_UINT(3, send_numbered(0, 3)); /* kept by the core */
    struct can_frame cf;
    TEST_ASSERT_EQUAL_INT(-1, read(pair[1], &cf, sizeof cf)); /* nothing on the bus yet */
    port.hold = false;
    co_node_tx_ready(&node);
    for (unsigned i = 0; i < 3; i++) {
        expect_peer_frame(0x181, 2, (uint8_t)i);
    }
    TEST_ASSERT_EQUAL_UINT32(0, node.stats.tx_dropped);
    close_pair();
}

static void test_filter_ids_cover_the_node(void)
{
    open_pair();
    start_node();
    uint16_t ids[SC_MAX_FILTERS];
    size_t n = sc_node_cob_ids(&node, ids, SC_MAX_FILTERS);
    const uint16_t must[] = {0x000, 0x080, 0x605, 0x705, 0x205, 0x305, 0x405, 0x505, 0x185};
    for (size_t i = 0; i < sizeof must / sizeof must[0]; i++) {
        bool found = false;
        for (size_t k = 0; k < n; k++) {
            found = found || ids[k] == must[i];
        }
        TEST_ASSERT_TRUE_MESSAGE(found, "a COB-ID of the node is missing from the filters");
    }
    close_pair();
}

/* --- loop: stdin, signals, sleeping -------------------------------------------------------------- */

typedef struct lines {
    char seen[4][32];
    int count;
    loop *lp;
} lines;

static void on_line(void *ctx, char *line, uint64_t now)
{
    lines *l = ctx;
    (void)now;
    if (l->count < 4) {
        snprintf(l->seen[l->count], sizeof l->seen[0], "%s", line);
    }
    l->count++;
    if (strcmp(line, "quit") == 0) {
        loop_stop(l->lp);
    }
}

typedef struct ticker {
    unsigned ticks;
    uint64_t period;
    uint64_t next;
    unsigned stop_after;
    loop *lp;
    bool send_signal;
} ticker;

static uint64_t ticker_process(void *ctx, uint64_t now)
{
    ticker *t = ctx;
    if (t->next == 0u) {
        t->next = now + t->period;
    }
    if (now >= t->next) {
        t->ticks++;
        t->next += t->period;
        if (t->ticks == t->stop_after) {
            if (t->send_signal) {
                kill(getpid(), SIGTERM);
            } else {
                loop_stop(t->lp);
            }
        }
    }
    return t->next;
}

static void no_rx(void *ctx, const co_frame *f, uint64_t now)
{
    (void)ctx;
    (void)f;
    (void)now;
}

static void no_tx_ready(void *ctx, uint64_t now)
{
    (void)ctx;
    (void)now;
}

static void test_loop_sleeps_until_the_deadline(void)
{
    open_pair();
    loop lp;
    TEST_ASSERT_EQUAL_INT(0, loop_init(&lp));
    ticker t = {0, 20000u, 0, 10, &lp, false};
    loop_member m = {&port, &t, no_rx, NULL, ticker_process, no_tx_ready, -1, NULL};
    TEST_ASSERT_EQUAL_INT(0, loop_add(&lp, &m));
    uint64_t start = loop_now();
    alarm(20);
    TEST_ASSERT_EQUAL_INT(0, loop_run(&lp));
    alarm(0);
    uint64_t took = loop_now() - start;
    TEST_ASSERT_TRUE(took >= 200000u);          /* 10 ticks of 20 ms */
    TEST_ASSERT_TRUE(lp.wakeups <= 15u);       /* one wake-up per tick, no polling */
    loop_close(&lp);
    close_pair();
}

/* Watched descriptors and tickers: two sockets ready in one batch, the first callback closes the
 * other and hands its slot to a fresh socket; the stale event of the batch reaches neither. */
typedef struct watchers {
    loop *lp;
    int fds[2];
    int fresh;
    unsigned calls[2];
    unsigned fresh_calls;
    uint64_t stop_at;
} watchers;

static void fresh_ready(void *ctx, uint32_t events, uint64_t now)
{
    watchers *wt = ctx;
    (void)events;
    (void)now;
    wt->fresh_calls++;
}

static void watched_ready(watchers *wt, int i)
{
    wt->calls[i]++;
    char buf[8];
    TEST_ASSERT_EQUAL_INT(1, (int)read(wt->fds[i], buf, sizeof buf));
    int other = wt->fds[1 - i];
    loop_unwatch_fd(wt->lp, other);
    TEST_ASSERT_EQUAL_INT(0, loop_watch_fd(wt->lp, wt->fresh, EPOLLIN, fresh_ready, wt));
}

static void watched0(void *ctx, uint32_t events, uint64_t now)
{
    (void)events;
    (void)now;
    watched_ready(ctx, 0);
}

static void watched1(void *ctx, uint32_t events, uint64_t now)
{
    (void)events;
    (void)now;
    watched_ready(ctx, 1);
}

static uint64_t stop_ticker(void *ctx, uint64_t now)
{
    watchers *wt = ctx;
    if (wt->stop_at == 0u) {
        wt->stop_at = now + 50000u;
    }
    if (now >= wt->stop_at) {
        loop_stop(wt->lp);
    }
    return wt->stop_at;
}

static void test_loop_watches_and_tickers(void)
{
    int a[2], b[2], c[2];
    TEST_ASSERT_EQUAL_INT(0, socketpair(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK, 0, a));
    TEST_ASSERT_EQUAL_INT(0, socketpair(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK, 0, b));
    TEST_ASSERT_EQUAL_INT(0, socketpair(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK, 0, c));
    loop lp;
    TEST_ASSERT_EQUAL_INT(0, loop_init(&lp));
    watchers wt = {&lp, {a[0], b[0]}, c[0], {0, 0}, 0, 0};
    TEST_ASSERT_EQUAL_INT(0, loop_watch_fd(&lp, a[0], EPOLLIN, watched0, &wt));
    TEST_ASSERT_EQUAL_INT(0, loop_watch_fd(&lp, b[0], EPOLLIN, watched1, &wt));
    TEST_ASSERT_EQUAL_INT(0, loop_add_ticker(&lp, stop_ticker, &wt));
    TEST_ASSERT_EQUAL_INT(1, (int)write(a[1], "x", 1));
    TEST_ASSERT_EQUAL_INT(1, (int)write(b[1], "y", 1));
    alarm(20);
    TEST_ASSERT_EQUAL_INT(0, loop_run(&lp));
    alarm(0);
    /* one of the two ran and unwatched the other before its event of the same batch */
    TEST_ASSERT_EQUAL_UINT(1, wt.calls[0] + wt.calls[1]);
    /* the fresh socket (nothing to read) took the freed slot: the stale event of the batch,
     * meant for the socket before it, never reaches it */
    TEST_ASSERT_EQUAL_UINT(0, wt.fresh_calls);
    TEST_ASSERT_TRUE(loop_now() >= wt.stop_at);
    TEST_ASSERT_EQUAL_INT(-1, loop_watch_fd(&lp, -1, EPOLLIN, fresh_ready, &wt));
    loop_close(&lp);
    for (int i = 0; i < 2; i++) {
        close(a[i]);
        close(b[i]);
        close(c[i]);
    }
}

static void test_loop_stdin_lines_and_sigterm(void)
{
    open_pair();
    int in[2];
    TEST_ASSERT_EQUAL_INT(0, pipe(in));
    loop lp;
    TEST_ASSERT_EQUAL_INT(0, loop_init(&lp));
    lines l = {{{0}}, 0, &lp};
    ticker t = {0, 10000u, 0, 5, &lp, true};
    loop_member m = {&port, &t, no_rx, NULL, ticker_process, no_tx_ready, -1, NULL};
    TEST_ASSERT_EQUAL_INT(0, loop_add(&lp, &m));
    TEST_ASSERT_EQUAL_INT(0, loop_watch_stdin(&lp, in[0], on_line, &l));
    const char text[] = "fault 5 0x01\n\nclear 5\npartial";
    TEST_ASSERT_EQUAL_INT(sizeof text - 1, write(in[1], text, sizeof text - 1));
    close(in[1]); /* end of file: the partial last line still counts; the loop keeps going */
    alarm(20);
    TEST_ASSERT_EQUAL_INT(0, loop_run(&lp));
    alarm(0);
    TEST_ASSERT_EQUAL_INT(SIGTERM, lp.signal);
    TEST_ASSERT_EQUAL_INT(4, l.count);
    TEST_ASSERT_EQUAL_STRING("fault 5 0x01", l.seen[0]);
    TEST_ASSERT_EQUAL_STRING("", l.seen[1]);
    TEST_ASSERT_EQUAL_STRING("clear 5", l.seen[2]);
    TEST_ASSERT_EQUAL_STRING("partial", l.seen[3]);
    TEST_ASSERT_EQUAL_UINT(5, t.ticks);
    loop_close(&lp);
    close(in[0]);
    close_pair();
}

static void test_loop_reads_a_file_on_stdin(void)
{
    open_pair();
    char file[320];
    snprintf(file, sizeof file, "%s/commands", dir);
    FILE *f = fopen(file, "w");
    TEST_ASSERT_NOT_NULL(f);
    fputs("status\nquit\nnever\n", f);
    fclose(f);
    int fd = open(file, O_RDONLY);
    TEST_ASSERT_TRUE(fd >= 0);
    loop lp;
    TEST_ASSERT_EQUAL_INT(0, loop_init(&lp));
    lines l = {{{0}}, 0, &lp};
    ticker t = {0, 1000000u, 0, 100, &lp, false};
    loop_member m = {&port, &t, no_rx, NULL, ticker_process, no_tx_ready, -1, NULL};
    TEST_ASSERT_EQUAL_INT(0, loop_add(&lp, &m));
    TEST_ASSERT_EQUAL_INT(0, loop_watch_stdin(&lp, fd, on_line, &l));
    alarm(20);
    TEST_ASSERT_EQUAL_INT(0, loop_run(&lp));
    alarm(0);
    TEST_ASSERT_EQUAL_INT(2, l.count); /* stopped at quit */
    TEST_ASSERT_EQUAL_STRING("quit", l.seen[1]);
    loop_close(&lp);
    close(fd);
    close_pair();
}

/* --- the benchmark device (--drive bench) ------------------------------------------------------- */

static void test_bench_device_domain_keeps_what_was_downloaded(void)
{
    char err[128];
    sim_node *sn = sim_bench_create(5, NULL, err, sizeof err);
    TEST_ASSERT_NOT_NULL_MESSAGE(sn, err);
    co_node *bench_node = sim_co_node(sn);
    uint32_t size = 300000u;
    uint8_t *data = malloc(size);
    uint8_t *back = malloc(SIM_BENCH_DOMAIN_CAP + 1u);
    TEST_ASSERT_NOT_NULL(data);
    TEST_ASSERT_NOT_NULL(back);
    for (uint32_t i = 0; i < size; i++) {
        data[i] = (uint8_t)(i * 7u + (i >> 8));
    }
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NONE, co_od_write(bench_node, 0x2000, 0, data, size,
                                                       CO_ORIGIN_SDO));
    uint32_t len = 0;
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NONE, co_od_read(bench_node, 0x2000, 0, back,
                                                      SIM_BENCH_DOMAIN_CAP + 1u, &len,
                                                      CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_UINT32(size, len);
    TEST_ASSERT_EQUAL_MEMORY(data, back, size);
    /* too big for the buffer: refused, and the object is empty rather than half overwritten */
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_OUT_OF_MEMORY,
                            co_od_write(bench_node, 0x2000, 0, back, SIM_BENCH_DOMAIN_CAP + 1u,
                                        CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NONE, co_od_read(bench_node, 0x2000, 0, back, 16, &len,
                                                      CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_UINT32(0, len);
    TEST_ASSERT_FALSE(sim_set(sn, "x=1", err, sizeof err));
    free(data);
    free(back);
    sim_node_destroy(sn);
}

/* --- the EtherCAT line ------------------------------------------------------------------------- */

/* An Ethernet frame with one datagram (cmd, adp, ado, len data bytes of 0), padded to 60 bytes.
 * Returns its length; the datagram's data starts at byte 26, its WKC at 26 + len. */
static size_t ecat_frame(uint8_t *f, uint8_t cmd, uint16_t adp, uint16_t ado, uint16_t len)
{
    memset(f, 0, 128);
    memset(f, 0xFF, 6);                        /* broadcast, as SOEM sends */
    f[6] = 0x00; f[11] = 0x01;                 /* source 00:00:00:00:00:01 */
    f[12] = 0x88; f[13] = 0xA4;
    uint16_t elen = (uint16_t)(10u + len + 2u);
    f[14] = (uint8_t)elen; f[15] = (uint8_t)(0x10u | (elen >> 8)); /* type 1: commands */
    f[16] = cmd; f[17] = 0x42;
    f[18] = (uint8_t)adp; f[19] = (uint8_t)(adp >> 8);
    f[20] = (uint8_t)ado; f[21] = (uint8_t)(ado >> 8);
    f[22] = (uint8_t)len; f[23] = (uint8_t)(len >> 8);
    size_t n = 26u + len + 2u;
    return n < 60u ? 60u : n;
}

static ssize_t send_enobufs(int fd, const void *buf, size_t len, int flags)
{
    (void)fd; (void)buf; (void)len; (void)flags;
    errno = ENOBUFS;
    return -1;
}

static void test_ecat_line_processes_frames_in_chain_order_and_sends_them_back(void)
{
    int sv[2];
    TEST_ASSERT_EQUAL_INT(0, socketpair(AF_UNIX, SOCK_DGRAM | SOCK_NONBLOCK, 0, sv));
    ecat_port ep;
    ecat_port_attach(&ep, sv[0], "test");
    char err[128];
    sim_node *sn[2];
    const co_drive_desc *desc = co_drive_registry_find("vf-mb1-ecat");
    TEST_ASSERT_NOT_NULL(desc);
    TEST_ASSERT_TRUE(ecat_drive_supported("vf-mb1-ecat"));
    TEST_ASSERT_FALSE(ecat_drive_supported("vf-s15"));
    for (unsigned i = 0; i < 2u; i++) {
        sn[i] = sim_node_create(desc, (uint8_t)(i + 1u), NULL, err, sizeof err);
        TEST_ASSERT_NOT_NULL_MESSAGE(sn[i], err);
        TEST_ASSERT_EQUAL_INT_MESSAGE(0, ecat_port_add(&ep, desc->id, &sn[i]->drive, err,
                                                       sizeof err), err);
    }
    TEST_ASSERT_EQUAL_INT(-1, ecat_port_add(&ep, "vf-s15", &sn[0]->drive, err, sizeof err));
    TEST_ASSERT_NOT_NULL(strstr(err, "no EtherCAT face"));
    for (unsigned i = 0; i < 2u; i++) {
        sim_start(sn[i], 1000u);
    }
    TEST_ASSERT_EQUAL_INT_MESSAGE(0, ecat_port_start(&ep, 1000u, err, sizeof err), err);

    /* BRD of the ESC type: both slaves answer (WKC 2), auto-increment addressing by position */
    uint8_t f[128], back[256];
    size_t n = ecat_frame(f, 0x07, 0x0000, 0x0000, 2);
    TEST_ASSERT_EQUAL_INT((int)n, (int)send(sv[1], f, n, 0));
    ecat_port_input(&ep, 2000u);
    ssize_t got = recv(sv[1], back, sizeof back, MSG_DONTWAIT);
    TEST_ASSERT_EQUAL_INT((int)n, (int)got);
    TEST_ASSERT_EQUAL_HEX8(0x42, back[17]);             /* same datagram */
    TEST_ASSERT_EQUAL_UINT16(2, back[28] | back[29] << 8); /* WKC: both ESCs */
    TEST_ASSERT_EQUAL_UINT16(2, back[18] | back[19] << 8); /* ADP counted up by each */
    TEST_ASSERT_EQUAL_HEX8(0x02, back[6] & 0x02);        /* the ESC marks the source MAC */

    /* APRD 0x0110 (DL status) of position 2 (ADP -1): the end of the line, port 1 closed */
    n = ecat_frame(f, 0x01, 0xFFFF, 0x0110, 2);
    send(sv[1], f, n, 0);
    ecat_port_input(&ep, 3000u);
    TEST_ASSERT_EQUAL_INT((int)n, (int)recv(sv[1], back, sizeof back, MSG_DONTWAIT));
    TEST_ASSERT_EQUAL_UINT16(1, back[28] | back[29] << 8);
    uint16_t dl_last = (uint16_t)(back[26] | back[27] << 8);
    n = ecat_frame(f, 0x01, 0x0000, 0x0110, 2);
    send(sv[1], f, n, 0);
    ecat_port_input(&ep, 4000u);
    TEST_ASSERT_EQUAL_INT((int)n, (int)recv(sv[1], back, sizeof back, MSG_DONTWAIT));
    uint16_t dl_first = (uint16_t)(back[26] | back[27] << 8);
    /* 0x0110 bit 5 link on port 1, bit 10 loop port 1 closed, bit 11 communication on port 1 */
    TEST_ASSERT_EQUAL_HEX16(0x0820, dl_first & 0x0C20);  /* port 1 open: the next slave */
    TEST_ASSERT_EQUAL_HEX16(0x0400, dl_last & 0x0C20);   /* port 1 looped back: the last one */

    /* a broken frame (length field past the end): not sent back, counted, nothing else */
    n = ecat_frame(f, 0x07, 0x0000, 0x0000, 2);
    f[14] = 0xFF;
    send(sv[1], f, n, 0);
    ecat_port_input(&ep, 5000u);
    TEST_ASSERT_EQUAL_INT(-1, (int)recv(sv[1], back, sizeof back, MSG_DONTWAIT));
    TEST_ASSERT_EQUAL_UINT32(1, ep.stats.rx_bad);
    TEST_ASSERT_EQUAL_UINT32(3, ep.stats.rx_frames);
    TEST_ASSERT_EQUAL_UINT32(3, ep.stats.tx_frames);

    /* a send that fails is counted: the master sees a lost frame and repeats */
    ep.sys_send = send_enobufs;
    n = ecat_frame(f, 0x07, 0x0000, 0x0000, 2);
    send(sv[1], f, n, 0);
    ecat_port_input(&ep, 6000u);
    TEST_ASSERT_EQUAL_UINT32(1, ep.stats.tx_errors);

    TEST_ASSERT_EQUAL_UINT8(CO_ECAT_STATE_INIT, co_ecat_slave_state(&ecat_port_slot(&ep, 1)->slave));
    TEST_ASSERT_NULL(ecat_port_slot(&ep, 3));
    TEST_ASSERT_NULL(ecat_port_slot(&ep, 0));

    ecat_port_close(&ep);
    close(sv[1]);
    for (unsigned i = 0; i < 2u; i++) {
        sim_node_destroy(sn[i]);
    }
}

/* --- what canopen-drive repeats of bad input ---------------------------------------------------- */

static void test_show_escapes_and_cuts_user_text(void)
{
    char buf[SIM_SHOW_BUF];
    TEST_ASSERT_EQUAL_STRING("frobnicate", sim_show("frobnicate", buf, sizeof buf));
    /* control bytes (a terminal escape sequence too), DEL, non-ASCII, the backslash itself */
    TEST_ASSERT_EQUAL_STRING("\\x01\\x7F\\xFF\\\\ \\x1B[2J",
                             sim_show("\x01\x7F\xFF\\ \x1B[2J", buf, sizeof buf));
    /* 120 kB of 'A': the first SIM_SHOW_MAX and "..." */
    size_t big = 120u * 1024u;
    char *arg = malloc(big + 1u);
    TEST_ASSERT_NOT_NULL(arg);
    memset(arg, 'A', big);
    arg[big] = '\0';
    sim_show(arg, buf, sizeof buf);
    TEST_ASSERT_EQUAL_size_t(SIM_SHOW_MAX + 3u, strlen(buf));
    TEST_ASSERT_EQUAL_STRING("...", buf + SIM_SHOW_MAX);
    /* exactly SIM_SHOW_MAX bytes: whole, no "..." */
    arg[SIM_SHOW_MAX] = '\0';
    TEST_ASSERT_EQUAL_size_t(SIM_SHOW_MAX, strlen(sim_show(arg, buf, sizeof buf)));
    /* every byte escaped still fits the buffer */
    memset(arg, 0x80, big);
    sim_show(arg, buf, sizeof buf);
    TEST_ASSERT_EQUAL_size_t(SIM_SHOW_MAX * 4u + 3u, strlen(buf));
    free(arg);
}

/* A flooded bus reports an overrun at every read (593 in 5 s were seen): the log gets one line
 * at once, then at most one a second with the count since the previous one, and the last held
 * back count is written when its second is over. */
static void test_receive_overruns_are_logged_once_a_second_with_their_count(void)
{
    open_pair();
    char err[128];
    sim_node *sn = sim_node_create(co_drive_registry_find("vf-s15"), 5, NULL, err, sizeof err);
    TEST_ASSERT_NOT_NULL_MESSAGE(sn, err);
    sc_attach(&sn->port, pair[0], "pair");
    sim_start(sn, 0);
    capture_begin(STDOUT_FILENO);
    uint64_t t = 1000u;
    for (int i = 0; i < 593; i++) {
        sim_bus_event(sn, SC_BUS_RX_OVERRUN, t);
        t += 8430u; /* 593 in 5 s */
    }
    uint64_t next = sim_process(sn, t);
    TEST_ASSERT_TRUE(next <= sn->overrun_logged_at + SIM_OVERRUN_LOG_US);
    (void)sim_process(sn, sn->overrun_logged_at + SIM_OVERRUN_LOG_US);
    const char *out = capture_end();
    unsigned logged = count_lines_with(out, "receive overrun");
    TEST_ASSERT_TRUE_MESSAGE(logged >= 2u && logged <= 7u, out);
    TEST_ASSERT_CONTAINS("node 5 vf-s15: CAN receive overrun\n", out);
    TEST_ASSERT_CONTAINS("(593 in all)", out);
    TEST_ASSERT_EQUAL_UINT32(593, sn->overruns);
    TEST_ASSERT_EQUAL_UINT32(0, sn->overruns_unlogged);
    /* other bus events are still logged each time */
    capture_begin(STDOUT_FILENO);
    sim_bus_event(sn, SC_BUS_ERROR_PASSIVE, t);
    sim_bus_event(sn, SC_BUS_ERROR_ACTIVE, t);
    out = capture_end();
    TEST_ASSERT_CONTAINS("CAN error passive", out);
    TEST_ASSERT_CONTAINS("CAN error active", out);
    sn->port.fd = -1; /* the pair is closed below */
    sim_node_destroy(sn);
    close_pair();
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_store_missing_file_is_empty);
    RUN_TEST(test_store_save_then_reload_in_new_process);
    RUN_TEST(test_store_several_nodes_in_one_file);
    RUN_TEST(test_store_corrupt_data_gives_defaults);
    RUN_TEST(test_store_corrupt_magic_gives_defaults);
    RUN_TEST(test_store_truncated_file_gives_defaults);
    RUN_TEST(test_store_crash_before_rename_keeps_old_values);
    RUN_TEST(test_store_failed_save_keeps_old_values);
    RUN_TEST(test_store_second_process_on_one_file_is_refused);
    RUN_TEST(test_store_refuses_what_is_not_a_regular_file);
    RUN_TEST(test_store_refuses_a_file_larger_than_any_store);
    RUN_TEST(test_store_crc32_check_value);
    RUN_TEST(test_recv_decodes_frames_and_error_frames);
    RUN_TEST(test_eagain_frames_wait_for_epollout_and_keep_order);
    RUN_TEST(test_enobufs_is_retried_after_a_delay);
    RUN_TEST(test_hold_keeps_frames_in_order_until_released);
    RUN_TEST(test_filter_ids_cover_the_node);
    RUN_TEST(test_loop_sleeps_until_the_deadline);
    RUN_TEST(test_loop_watches_and_tickers);
    RUN_TEST(test_loop_stdin_lines_and_sigterm);
    RUN_TEST(test_loop_reads_a_file_on_stdin);
    RUN_TEST(test_bench_device_domain_keeps_what_was_downloaded);
    RUN_TEST(test_ecat_line_processes_frames_in_chain_order_and_sends_them_back);
    RUN_TEST(test_show_escapes_and_cuts_user_text);
    RUN_TEST(test_receive_overruns_are_logged_once_a_second_with_their_count);
    return UNITY_END();
}
