/* watch.c — what a student's code tries outside its directory, seen.
 *
 * sidx-check links the student's program with -Wl,--wrap=open,... (the
 * list in sidx_check.c, ck_watch_wraps): every call of these C library
 * functions, from any object of the program, comes here first.  While
 * ck_watch_fd is set (the runner sets it in the case's process just
 * before the student's function runs) a call that reaches outside the
 * case's directory — a path that is absolute or climbs above it with
 * "..", a network connection, a new process or program, a signal to
 * another process — is written to ck_watch_fd as one line
 * "KIND<TAB>RESULT<TAB>WHAT" (RESULT: "ok", or the error it got), and the
 * call goes on to the C library.  The namespaces (sandbox.c) refuse it;
 * this only makes the attempt visible, so a call it misses (a system call
 * made directly) is still refused, only not listed. */
#define _GNU_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <arpa/inet.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

int ck_watch_fd = -1;
static int logged;
#define CK_WATCH_MAX 64 /* lines per process: a loop of attempts is one attempt */

/* 1 if path leaves the directory it is read from: absolute, or ".." more
 * often than it went down. */
static int outside(const char *path)
{
    if (!path) return 0;
    if (path[0] == '/') return 1;
    int depth = 0;
    for (const char *p = path; *p;) {
        const size_t n = strcspn(p, "/");
        if (n == 2 && p[0] == '.' && p[1] == '.') {
            if (--depth < 0) return 1;
        } else if (n > 0 && !(n == 1 && p[0] == '.')) {
            ++depth;
        }
        p += n;
        p += strspn(p, "/");
    }
    return 0;
}

static void note(const char *kind, int ok, int err, const char *what)
{
    if (ck_watch_fd < 0 || logged >= CK_WATCH_MAX) return;
    ++logged;
    char line[600];
    const int n = snprintf(line, sizeof line, "%s\t%s\t%.500s\n", kind, ok ? "ok" : strerror(err), what ? what : "");
    if (n > 0 && write(ck_watch_fd, line, (size_t)n < sizeof line ? (size_t)n : sizeof line - 1) < 0) {
    }
}

/* a path call: noted if the path leaves the directory; errno kept */
static void note_path(const char *kind, int ok, const char *path)
{
    const int err = errno;
    if (ck_watch_fd >= 0 && outside(path)) note(kind, ok, err, path);
    errno = err;
}

static const char *open_kind(int flags)
{
    return (flags & (O_WRONLY | O_RDWR | O_CREAT | O_TRUNC | O_APPEND)) ? "write" : "read";
}

static const char *fopen_kind(const char *mode)
{
    return mode && (strchr(mode, 'w') || strchr(mode, 'a') || strchr(mode, '+')) ? "write" : "read";
}

int __real_open(const char *path, int flags, ...);
int __real_open64(const char *path, int flags, ...);
int __real_openat(int dirfd, const char *path, int flags, ...);
int __real_openat64(int dirfd, const char *path, int flags, ...);
int __real_creat(const char *path, mode_t mode);
int __real_creat64(const char *path, mode_t mode);
FILE *__real_fopen(const char *path, const char *mode);
FILE *__real_fopen64(const char *path, const char *mode);
FILE *__real_freopen(const char *path, const char *mode, FILE *f);
int __real_mkdir(const char *path, mode_t mode);
int __real_unlink(const char *path);
int __real_remove(const char *path);
int __real_rmdir(const char *path);
int __real_rename(const char *from, const char *to);
int __real_link(const char *from, const char *to);
int __real_symlink(const char *from, const char *to);
int __real_truncate(const char *path, off_t len);
int __real_chmod(const char *path, mode_t mode);
int __real_connect(int fd, const struct sockaddr *a, socklen_t len);
pid_t __real_fork(void);
int __real_system(const char *cmd);
FILE *__real_popen(const char *cmd, const char *mode);
int __real_execve(const char *path, char *const argv[], char *const envp[]);
int __real_execv(const char *path, char *const argv[]);
int __real_execvp(const char *file, char *const argv[]);
int __real_kill(pid_t pid, int sig);

static mode_t mode_arg(int flags, va_list ap)
{
    return (flags & O_CREAT) || (flags & O_TMPFILE) == O_TMPFILE ? (mode_t)va_arg(ap, int) : 0;
}

int __wrap_open(const char *path, int flags, ...)
{
    va_list ap;
    va_start(ap, flags);
    const mode_t mode = mode_arg(flags, ap);
    va_end(ap);
    const int r = __real_open(path, flags, mode);
    note_path(open_kind(flags), r >= 0, path);
    return r;
}

int __wrap_open64(const char *path, int flags, ...)
{
    va_list ap;
    va_start(ap, flags);
    const mode_t mode = mode_arg(flags, ap);
    va_end(ap);
    const int r = __real_open64(path, flags, mode);
    note_path(open_kind(flags), r >= 0, path);
    return r;
}

int __wrap_openat(int dirfd, const char *path, int flags, ...)
{
    va_list ap;
    va_start(ap, flags);
    const mode_t mode = mode_arg(flags, ap);
    va_end(ap);
    const int r = __real_openat(dirfd, path, flags, mode);
    note_path(open_kind(flags), r >= 0, path);
    return r;
}

int __wrap_openat64(int dirfd, const char *path, int flags, ...)
{
    va_list ap;
    va_start(ap, flags);
    const mode_t mode = mode_arg(flags, ap);
    va_end(ap);
    const int r = __real_openat64(dirfd, path, flags, mode);
    note_path(open_kind(flags), r >= 0, path);
    return r;
}

int __wrap_creat(const char *path, mode_t mode)
{
    const int r = __real_creat(path, mode);
    note_path("write", r >= 0, path);
    return r;
}

int __wrap_creat64(const char *path, mode_t mode)
{
    const int r = __real_creat64(path, mode);
    note_path("write", r >= 0, path);
    return r;
}

FILE *__wrap_fopen(const char *path, const char *mode)
{
    FILE *f = __real_fopen(path, mode);
    note_path(fopen_kind(mode), f != NULL, path);
    return f;
}

FILE *__wrap_fopen64(const char *path, const char *mode)
{
    FILE *f = __real_fopen64(path, mode);
    note_path(fopen_kind(mode), f != NULL, path);
    return f;
}

FILE *__wrap_freopen(const char *path, const char *mode, FILE *s)
{
    FILE *f = __real_freopen(path, mode, s);
    note_path(fopen_kind(mode), f != NULL, path);
    return f;
}

int __wrap_mkdir(const char *path, mode_t mode)
{
    const int r = __real_mkdir(path, mode);
    note_path("write", r == 0, path);
    return r;
}

int __wrap_unlink(const char *path)
{
    const int r = __real_unlink(path);
    note_path("remove", r == 0, path);
    return r;
}

int __wrap_remove(const char *path)
{
    const int r = __real_remove(path);
    note_path("remove", r == 0, path);
    return r;
}

int __wrap_rmdir(const char *path)
{
    const int r = __real_rmdir(path);
    note_path("remove", r == 0, path);
    return r;
}

int __wrap_rename(const char *from, const char *to)
{
    const int r = __real_rename(from, to);
    note_path("write", r == 0, outside(to) ? to : from);
    return r;
}

int __wrap_link(const char *from, const char *to)
{
    const int r = __real_link(from, to);
    note_path("write", r == 0, outside(to) ? to : from);
    return r;
}

int __wrap_symlink(const char *from, const char *to)
{
    const int r = __real_symlink(from, to);
    note_path("write", r == 0, outside(to) ? to : from);
    return r;
}

int __wrap_truncate(const char *path, off_t len)
{
    const int r = __real_truncate(path, len);
    note_path("write", r == 0, path);
    return r;
}

int __wrap_chmod(const char *path, mode_t mode)
{
    const int r = __real_chmod(path, mode);
    note_path("write", r == 0, path);
    return r;
}

int __wrap_connect(int fd, const struct sockaddr *a, socklen_t len)
{
    const int r = __real_connect(fd, a, len);
    const int err = errno;
    char what[300] = "a socket";
    if (a && a->sa_family == AF_INET && len >= sizeof(struct sockaddr_in)) {
        const struct sockaddr_in *in = (const struct sockaddr_in *)a;
        char ip[INET_ADDRSTRLEN] = "?";
        inet_ntop(AF_INET, &in->sin_addr, ip, sizeof ip);
        snprintf(what, sizeof what, "%s:%u", ip, (unsigned)ntohs(in->sin_port));
    } else if (a && a->sa_family == AF_INET6 && len >= sizeof(struct sockaddr_in6)) {
        const struct sockaddr_in6 *in = (const struct sockaddr_in6 *)a;
        char ip[INET6_ADDRSTRLEN] = "?";
        inet_ntop(AF_INET6, &in->sin6_addr, ip, sizeof ip);
        snprintf(what, sizeof what, "[%s]:%u", ip, (unsigned)ntohs(in->sin6_port));
    } else if (a && a->sa_family == AF_UNIX) {
        snprintf(what, sizeof what, "%.200s", ((const struct sockaddr_un *)a)->sun_path);
    }
    note("connect", r == 0, err, what);
    errno = err;
    return r;
}

pid_t __wrap_fork(void)
{
    const pid_t r = __real_fork();
    if (r != 0) { /* the parent notes it (a child has nothing to note) */
        const int err = errno;
        note("process", r > 0, err, "fork");
        errno = err;
    }
    return r;
}

int __wrap_system(const char *cmd)
{
    const int r = __real_system(cmd);
    const int err = errno;
    /* 127: the shell could not be run (there is none in the sandbox) */
    const int ran = r != -1 && !(WIFEXITED(r) && WEXITSTATUS(r) == 127);
    note("process", ran, r == -1 ? err : ENOENT, cmd ? cmd : "system");
    errno = err;
    return r;
}

FILE *__wrap_popen(const char *cmd, const char *mode)
{
    FILE *f = __real_popen(cmd, mode);
    const int err = errno;
    note("process", f != NULL, err, cmd);
    errno = err;
    return f;
}

int __wrap_execve(const char *path, char *const argv[], char *const envp[])
{
    const int r = __real_execve(path, argv, envp);
    note("process", 0, errno, path);
    return r;
}

int __wrap_execv(const char *path, char *const argv[])
{
    const int r = __real_execv(path, argv);
    note("process", 0, errno, path);
    return r;
}

int __wrap_execvp(const char *file, char *const argv[])
{
    const int r = __real_execvp(file, argv);
    note("process", 0, errno, file);
    return r;
}

int __wrap_kill(pid_t pid, int sig)
{
    const int r = __real_kill(pid, sig);
    if (ck_watch_fd >= 0 && pid != getpid()) {
        const int err = errno;
        char what[64];
        if (pid == -1) snprintf(what, sizeof what, "signal %d to every process (kill -1)", sig);
        else if (pid == 0) snprintf(what, sizeof what, "signal %d to its process group", sig);
        else snprintf(what, sizeof what, "signal %d to %s %d", sig, pid < 0 ? "process group" : "process", (int)(pid < 0 ? -pid : pid));
        note("signal", r == 0, err, what);
        errno = err;
    }
    return r;
}

/* An allocation that fails is no attempt outside, but it names the crash
 * that usually follows (a NULL written to): the runner reports the case
 * as out of memory, with the size asked for. */
void *__real_malloc(size_t size);
void *__real_calloc(size_t n, size_t size);
void *__real_realloc(void *p, size_t size);

static void note_alloc(const char *fn, size_t size)
{
    const int err = errno;
    char what[64];
    snprintf(what, sizeof what, "%s(%zu)", fn, size);
    if (ck_watch_fd >= 0) {
        char line[128];
        const int n = snprintf(line, sizeof line, "memory\t%s\t%s\n", strerror(err), what);
        if (n > 0 && write(ck_watch_fd, line, (size_t)n) < 0) {
        }
    }
    errno = err;
}

void *__wrap_malloc(size_t size)
{
    void *p = __real_malloc(size);
    if (!p && size) note_alloc("malloc", size);
    return p;
}

void *__wrap_calloc(size_t n, size_t size)
{
    void *p = __real_calloc(n, size);
    if (!p && n && size) note_alloc("calloc", n * size);
    return p;
}

void *__wrap_realloc(void *q, size_t size)
{
    void *p = __real_realloc(q, size);
    if (!p && size) note_alloc("realloc", size);
    return p;
}
