/* File-backed co_storage: all nodes' images in one file, replaced atomically on every store. */
#define _GNU_SOURCE
#include "file_store.h"

#include <errno.h>
#include <fcntl.h>
#include <libgen.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#define MAGIC "CODSTOR1"
#define MAGIC_LEN 8u
#define VERSION 1u
#define HEADER_LEN (MAGIC_LEN + 8u)
#define RECORD_HEAD_LEN (4u + FILE_STORE_DRIVE_LEN + 12u)

uint32_t file_store_crc32(uint32_t crc, const uint8_t *data, uint32_t len)
{
    crc = ~crc;
    for (uint32_t i = 0; i < len; i++) {
        crc ^= data[i];
        for (int b = 0; b < 8; b++) {
            crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
        }
    }
    return ~crc;
}

static void report(const file_store *store, const char *fmt, const char *detail)
{
    fprintf(stderr, "canopen-drive: store %s: ", store->path);
    fprintf(stderr, fmt, detail);
    fputc('\n', stderr);
}

static uint32_t get32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

static void put32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
    p[2] = (uint8_t)(v >> 16);
    p[3] = (uint8_t)(v >> 24);
}

static uint32_t padded(uint32_t len)
{
    return (len + 3u) & ~3u;
}

static void free_records(file_store_record *records, uint32_t count)
{
    for (uint32_t i = 0; i < count; i++) {
        free(records[i].data);
        records[i].data = NULL;
    }
}

/* Parses a whole file image into store->records. Returns NULL or the reason it is invalid. */
static const char *parse(file_store *store, const uint8_t *buf, size_t size)
{
    if (size < HEADER_LEN + 4u) {
        return "too short to be a store file";
    }
    if (memcmp(buf, MAGIC, MAGIC_LEN) != 0) {
        return "not a canopen-drive store file (bad magic)";
    }
    if (get32(buf + MAGIC_LEN) != VERSION) {
        return "unsupported format version";
    }
    if (file_store_crc32(0, buf, (uint32_t)(size - 4u)) != get32(buf + size - 4u)) {
        return "file checksum mismatch (damaged or truncated)";
    }
    uint32_t count = get32(buf + MAGIC_LEN + 4u);
    if (count > FILE_STORE_MAX_RECORDS) {
        return "too many records";
    }
    size_t pos = HEADER_LEN;
    size_t end = size - 4u;
    for (uint32_t i = 0; i < count; i++) {
        if (end - pos < RECORD_HEAD_LEN) {
            return "record header runs past the end";
        }
        const uint8_t *r = buf + pos;
        file_store_record rec;
        memset(&rec, 0, sizeof rec);
        rec.node_id = r[0];
        memcpy(rec.drive, r + 4, FILE_STORE_DRIVE_LEN);
        rec.drive[FILE_STORE_DRIVE_LEN - 1u] = '\0';
        rec.layout_hash = get32(r + 4 + FILE_STORE_DRIVE_LEN);
        rec.length = get32(r + 8 + FILE_STORE_DRIVE_LEN);
        uint32_t crc = get32(r + 12 + FILE_STORE_DRIVE_LEN);
        pos += RECORD_HEAD_LEN;
        if (rec.node_id < 1u || rec.node_id > 127u) {
            return "record with a node-ID outside 1..127";
        }
        if (rec.length > FILE_STORE_MAX_IMAGE || end - pos < padded(rec.length)) {
            return "record data runs past the end";
        }
        if (file_store_crc32(0, buf + pos, rec.length) != crc) {
            return "record checksum mismatch";
        }
        for (uint32_t k = 0; k < store->record_count; k++) {
            if (store->records[k].node_id == rec.node_id) {
                return "two records for one node-ID";
            }
        }
        rec.data = malloc(rec.length != 0u ? rec.length : 1u);
        if (rec.data == NULL) {
            return "out of memory";
        }
        memcpy(rec.data, buf + pos, rec.length);
        pos += padded(rec.length);
        store->records[store->record_count++] = rec;
    }
    if (pos != end) {
        return "trailing bytes after the last record";
    }
    return NULL;
}

/* What a path that is not a regular file is, for messages. */
static const char *file_kind(mode_t mode)
{
    if (S_ISDIR(mode)) {
        return "a directory";
    }
    if (S_ISFIFO(mode)) {
        return "a FIFO (named pipe)";
    }
    if (S_ISCHR(mode)) {
        return "a character device";
    }
    if (S_ISBLK(mode)) {
        return "a block device";
    }
    if (S_ISSOCK(mode)) {
        return "a socket";
    }
    return "not a regular file";
}

/* A store file must be a regular file (or absent) no larger than the layout allows. Checked with
 * stat(), which opens nothing: opening a FIFO would wait for a writer. */
static bool usable_path(const file_store *store, const struct stat *st)
{
    if (!S_ISREG(st->st_mode)) {
        fprintf(stderr,
                "canopen-drive: store %s: is %s, not a regular file: give the name of a store "
                "file (it is created by the first save)\n",
                store->path, file_kind(st->st_mode));
        return false;
    }
    if ((unsigned long long)st->st_size > (unsigned long long)FILE_STORE_MAX_FILE) {
        fprintf(stderr,
                "canopen-drive: store %s: is %lld bytes, larger than any store file can be (at "
                "most %lu bytes): not a store file\n",
                store->path, (long long)st->st_size, (unsigned long)FILE_STORE_MAX_FILE);
        return false;
    }
    return true;
}

/* Takes the exclusive lock on "<path>.lock" (see file_store.h) and writes this process's ID into
 * it. False with the reason on stderr. */
static bool take_lock(file_store *store)
{
    size_t plen = strlen(store->path);
    char *lock = malloc(plen + 6u);
    if (lock == NULL) {
        report(store, "%s", "out of memory");
        return false;
    }
    memcpy(lock, store->path, plen);
    memcpy(lock + plen, ".lock", 6u);
    bool ok = false;
    /* O_NONBLOCK: should the lock file be a FIFO, opening it does not wait for a writer. */
    int fd = open(lock, O_RDWR | O_CREAT | O_NONBLOCK | O_CLOEXEC, 0644);
    struct stat st;
    if (fd < 0) {
        fprintf(stderr,
                "canopen-drive: store %s: cannot create the lock file %s (%s); it keeps a second "
                "process off the store file\n",
                store->path, lock, strerror(errno));
        goto out;
    }
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        fprintf(stderr, "canopen-drive: store %s: the lock file %s is not a regular file\n",
                store->path, lock);
        goto out;
    }
    if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
        if (errno == EWOULDBLOCK) {
            char owner[32] = "";
            ssize_t n = pread(fd, owner, sizeof owner - 1u, 0);
            owner[n > 0 ? (size_t)n : 0u] = '\0';
            owner[strcspn(owner, "\n")] = '\0';
            fprintf(stderr,
                    "canopen-drive: store %s: in use by another process%s%s%s, which holds "
                    "%s: one store file serves one process, or the saves of one would silently "
                    "replace the other's; give this process a store file of its own\n",
                    store->path, owner[0] != '\0' ? " (process " : "", owner,
                    owner[0] != '\0' ? ")" : "", lock);
        } else {
            fprintf(stderr, "canopen-drive: store %s: cannot lock %s: %s\n", store->path, lock,
                    strerror(errno));
        }
        goto out;
    }
    char pid[32];
    int len = snprintf(pid, sizeof pid, "%ld\n", (long)getpid());
    if (ftruncate(fd, 0) != 0 || pwrite(fd, pid, (size_t)len, 0) != (ssize_t)len) {
        /* The lock holds without the text: it only names the owner in the message above. */
    }
    store->lock_fd = fd;
    fd = -1;
    ok = true;
out:
    if (fd >= 0) {
        close(fd);
    }
    free(lock);
    return ok;
}

/* Reads the whole regular file at store->path into a malloc'ed buffer (*buf, *size). NULL, or the
 * reason it cannot be read (then *buf is NULL). */
static const char *read_whole(file_store *store, uint8_t **buf, size_t *size)
{
    *buf = NULL;
    *size = 0;
    int fd = open(store->path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        return errno == ENOENT ? NULL : strerror(errno);
    }
    struct stat st;
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode) ||
        (unsigned long long)st.st_size > (unsigned long long)FILE_STORE_MAX_FILE) {
        close(fd); /* replaced between the checks and the open */
        return "it changed while it was opened";
    }
    size_t cap = (size_t)st.st_size + 1u; /* one more: a file that grew is noticed */
    uint8_t *data = malloc(cap);
    if (data == NULL) {
        close(fd);
        return "out of memory";
    }
    size_t got = 0;
    const char *why = NULL;
    while (got < cap) {
        ssize_t n = read(fd, data + got, cap - got);
        if (n < 0 && errno == EINTR) {
            continue;
        }
        if (n < 0) {
            why = strerror(errno);
            break;
        }
        if (n == 0) {
            break;
        }
        got += (size_t)n;
    }
    close(fd);
    if (why == NULL && got == cap) {
        why = "it grew while it was read";
    }
    if (why != NULL) {
        free(data);
        return why;
    }
    *buf = data;
    *size = got;
    return NULL;
}

bool file_store_open(file_store *store, const char *path)
{
    memset(store, 0, sizeof *store);
    store->lock_fd = -1;
    store->path = strdup(path);
    if (store->path == NULL) {
        fprintf(stderr, "canopen-drive: store %s: out of memory\n", path);
        return false;
    }
    struct stat st;
    if ((stat(path, &st) == 0 && !usable_path(store, &st)) || !take_lock(store)) {
        file_store_close(store);
        return false;
    }
    uint8_t *buf;
    size_t size;
    const char *why = read_whole(store, &buf, &size);
    if (why != NULL) {
        report(store, "cannot read it (%s): every node starts from its defaults", why);
        return true;
    }
    if (buf == NULL) {
        return true; /* no file yet: an empty store */
    }
    why = parse(store, buf, size);
    free(buf);
    if (why != NULL) {
        free_records(store->records, store->record_count);
        store->record_count = 0;
        report(store,
               "ignored: %s; every node starts from its defaults and the next store (0x1010) "
               "rewrites the file",
               why);
        return true;
    }
    store->loaded_ok = true;
    return true;
}

void file_store_close(file_store *store)
{
    free_records(store->records, store->record_count);
    store->record_count = 0;
    free(store->path);
    store->path = NULL;
    if (store->lock_fd >= 0) {
        close(store->lock_fd); /* releases the flock */
    }
    store->lock_fd = -1;
}

co_storage file_store_storage(file_store *store, file_store_slot *slot, uint8_t node_id,
                              const char *drive)
{
    memset(slot, 0, sizeof *slot);
    slot->store = store;
    slot->node_id = node_id;
    snprintf(slot->drive, sizeof slot->drive, "%s", drive);
    co_storage storage = {file_store_load, file_store_save, file_store_erase, slot};
    return storage;
}

static file_store_record *find(file_store *store, uint8_t node_id)
{
    for (uint32_t i = 0; i < store->record_count; i++) {
        if (store->records[i].node_id == node_id) {
            return &store->records[i];
        }
    }
    return NULL;
}

bool file_store_load(void *ctx, uint32_t layout_hash, uint32_t offset, uint8_t *buf, uint32_t len)
{
    file_store_slot *slot = ctx;
    file_store_record *rec = find(slot->store, slot->node_id);
    if (rec == NULL) {
        return false;
    }
    if (strcmp(rec->drive, slot->drive) != 0 || rec->layout_hash != layout_hash) {
        if (!slot->warned) {
            fprintf(stderr,
                    "canopen-drive: store %s: node %u: the stored values belong to %s (layout "
                    "0x%08X), not %s (layout 0x%08X): ignored, defaults used\n",
                    slot->store->path, (unsigned)slot->node_id, rec->drive,
                    (unsigned)rec->layout_hash, slot->drive, (unsigned)layout_hash);
            slot->warned = true;
        }
        return false;
    }
    if (offset > rec->length || len > rec->length - offset) {
        return false;
    }
    memcpy(buf, rec->data + offset, len);
    return true;
}

/* Writes buf to path atomically: temporary file, fsync, rename, fsync of the directory. */
static bool write_atomic(const char *path, const uint8_t *buf, size_t len, char *why, size_t cap)
{
    size_t plen = strlen(path);
    char *tmp = malloc(plen + 5u);
    char *dircopy = strdup(path);
    if (tmp == NULL || dircopy == NULL) {
        free(tmp);
        free(dircopy);
        snprintf(why, cap, "out of memory");
        return false;
    }
    memcpy(tmp, path, plen);
    memcpy(tmp + plen, ".tmp", 5u);
    bool ok = false;
    int fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) {
        snprintf(why, cap, "cannot create %s: %s", tmp, strerror(errno));
        goto out;
    }
    for (size_t done = 0; done < len;) {
        ssize_t n = write(fd, buf + done, len - done);
        if (n < 0 && errno == EINTR) {
            continue;
        }
        if (n <= 0) {
            snprintf(why, cap, "cannot write %s: %s", tmp, n < 0 ? strerror(errno) : "no space");
            close(fd);
            unlink(tmp);
            goto out;
        }
        done += (size_t)n;
    }
    if (fsync(fd) != 0) {
        snprintf(why, cap, "fsync %s: %s", tmp, strerror(errno));
        close(fd);
        unlink(tmp);
        goto out;
    }
    if (close(fd) != 0) {
        snprintf(why, cap, "close %s: %s", tmp, strerror(errno));
        unlink(tmp);
        goto out;
    }
    if (rename(tmp, path) != 0) {
        snprintf(why, cap, "rename %s: %s", tmp, strerror(errno));
        unlink(tmp);
        goto out;
    }
    /* The rename itself is durable only once the directory is. */
    int dfd = open(dirname(dircopy), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dfd >= 0) {
        (void)fsync(dfd);
        close(dfd);
    }
    ok = true;
out:
    free(tmp);
    free(dircopy);
    return ok;
}

/* Serialises records (with `replace` standing in for node `node_id`, or that node removed when
 * replace is NULL) and writes the file. */
static bool rewrite(file_store *store, uint8_t node_id, const file_store_record *replace)
{
    const file_store_record *list[FILE_STORE_MAX_RECORDS];
    uint32_t count = 0;
    size_t size = HEADER_LEN + 4u;
    for (uint32_t i = 0; i < store->record_count; i++) {
        if (store->records[i].node_id != node_id) {
            list[count++] = &store->records[i];
        }
    }
    if (replace != NULL && count < FILE_STORE_MAX_RECORDS) {
        list[count++] = replace;
    }
    for (uint32_t i = 0; i < count; i++) {
        size += RECORD_HEAD_LEN + padded(list[i]->length);
    }
    uint8_t *buf = calloc(1, size);
    if (buf == NULL) {
        report(store, "cannot store: %s", "out of memory");
        return false;
    }
    memcpy(buf, MAGIC, MAGIC_LEN);
    put32(buf + MAGIC_LEN, VERSION);
    put32(buf + MAGIC_LEN + 4u, count);
    size_t pos = HEADER_LEN;
    for (uint32_t i = 0; i < count; i++) {
        const file_store_record *r = list[i];
        buf[pos] = r->node_id;
        memcpy(buf + pos + 4u, r->drive, strnlen(r->drive, FILE_STORE_DRIVE_LEN - 1u));
        put32(buf + pos + 4u + FILE_STORE_DRIVE_LEN, r->layout_hash);
        put32(buf + pos + 8u + FILE_STORE_DRIVE_LEN, r->length);
        put32(buf + pos + 12u + FILE_STORE_DRIVE_LEN, file_store_crc32(0, r->data, r->length));
        pos += RECORD_HEAD_LEN;
        memcpy(buf + pos, r->data, r->length);
        pos += padded(r->length);
    }
    put32(buf + pos, file_store_crc32(0, buf, (uint32_t)pos));
    char why[512];
    bool ok = write_atomic(store->path, buf, size, why, sizeof why);
    free(buf);
    if (!ok) {
        report(store, "store failed, the file is unchanged: %s", why);
        return false;
    }
    store->saves++;
    return true;
}

bool file_store_save(void *ctx, uint32_t layout_hash, const uint8_t *image, uint32_t len)
{
    file_store_slot *slot = ctx;
    file_store *store = slot->store;
    if (len > FILE_STORE_MAX_IMAGE) {
        return false;
    }
    file_store_record fresh;
    memset(&fresh, 0, sizeof fresh);
    fresh.node_id = slot->node_id;
    memcpy(fresh.drive, slot->drive, sizeof fresh.drive);
    fresh.layout_hash = layout_hash;
    fresh.length = len;
    fresh.data = malloc(len != 0u ? len : 1u);
    if (fresh.data == NULL) {
        return false;
    }
    memcpy(fresh.data, image, len);
    file_store_record *old = find(store, slot->node_id);
    if (old == NULL && store->record_count >= FILE_STORE_MAX_RECORDS) {
        free(fresh.data);
        return false;
    }
    if (!rewrite(store, slot->node_id, &fresh)) {
        free(fresh.data); /* memory and file keep the old image */
        return false;
    }
    if (old != NULL) {
        free(old->data);
        *old = fresh;
    } else {
        store->records[store->record_count++] = fresh;
    }
    slot->warned = false;
    return true;
}

bool file_store_erase(void *ctx)
{
    file_store_slot *slot = ctx;
    file_store *store = slot->store;
    file_store_record *old = find(store, slot->node_id);
    if (old == NULL) {
        return true;
    }
    if (!rewrite(store, slot->node_id, NULL)) {
        return false;
    }
    free(old->data);
    *old = store->records[--store->record_count];
    memset(&store->records[store->record_count], 0, sizeof store->records[0]);
    return true;
}
