/* sandbox.c — the student's code in namespaces (sandbox.h).
 *
 * The kernel's own containers (namespaces(7), user_namespaces(7)): an
 * ordinary user may create a user namespace, in which it holds the
 * capabilities to make the others and to chroot; it maps only its own
 * uid, so nothing made there belongs to anyone else.  Root needs no user
 * namespace and drops to nobody instead.  bubblewrap (bwrap) is built on
 * the same calls and, unprivileged as Debian installs it, can do no more;
 * made here directly they cost a case no extra program and no extra
 * process: the PID namespace is made by the checker for each case's
 * child (unshare, fork, then setns back), which is its init. */
#define _GNU_SOURCE /* unshare, setns, CLONE_* */
#include "sandbox.h"

#include <errno.h>
#include <fcntl.h>
#include <grp.h>
#include <linux/capability.h>
#include <sched.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mount.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

static int own_pid_ns = -1; /* the checker's PID namespace, to return to after each fork */
static pid_t forward_to;

/* The checker, init of its PID namespace, takes only SIGKILL from
 * outside: Ctrl-C on the waiting process stops it that way. */
static void forward(int sig)
{
    (void)sig;
    kill(forward_to, SIGKILL);
}

static int fail(char *why, size_t size, const char *step)
{
    snprintf(why, size, "%s: %s", step, strerror(errno));
    return -1;
}

/* Writes text to the /proc file path (a uid or gid map, setgroups). */
static int write_file(const char *path, const char *text)
{
    const int fd = open(path, O_WRONLY | O_CLOEXEC);
    if (fd < 0) return -1;
    const size_t n = strlen(text);
    const ssize_t k = write(fd, text, n);
    const int saved = errno;
    close(fd);
    errno = saved;
    return k == (ssize_t)n ? 0 : -1;
}

int ck_sandbox_init(char *why, size_t size)
{
    if (own_pid_ns >= 0) return 0;
    const uid_t uid = geteuid();
    const gid_t gid = getegid();
    if (uid != 0) {
        if (unshare(CLONE_NEWUSER) != 0)
            return fail(why, size, "unshare (a user namespace, which this system refuses to ordinary users)");
        char map[64];
        if (write_file("/proc/self/setgroups", "deny") != 0) return fail(why, size, "setgroups deny");
        snprintf(map, sizeof map, "%u %u 1\n", (unsigned)uid, (unsigned)uid);
        if (write_file("/proc/self/uid_map", map) != 0) return fail(why, size, "uid_map");
        snprintf(map, sizeof map, "%u %u 1\n", (unsigned)gid, (unsigned)gid);
        if (write_file("/proc/self/gid_map", map) != 0) return fail(why, size, "gid_map");
        /* Returning to a PID namespace (setns, after each case's fork)
         * wants the capability in the user namespace that owns it: the
         * checker's original one is the system's.  So the checker goes on
         * in a PID namespace of its own, as its first process; this
         * process only waits for it and ends as it ends. */
        if (unshare(CLONE_NEWPID) != 0) return fail(why, size, "unshare (a PID namespace)");
        fflush(stdout);
        fflush(stderr);
        const pid_t child = fork();
        if (child < 0) return fail(why, size, "fork");
        if (child > 0) {
            static const int stop[] = {SIGINT, SIGTERM, SIGHUP, SIGQUIT};
            forward_to = child;
            for (size_t k = 0; k < sizeof stop / sizeof stop[0]; ++k) signal(stop[k], forward);
            int st;
            while (waitpid(child, &st, 0) < 0)
                if (errno != EINTR) _exit(2);
            if (WIFEXITED(st)) _exit(WEXITSTATUS(st));
            signal(WTERMSIG(st), SIG_DFL);
            raise(WTERMSIG(st));
            _exit(2);
        }
    }
    own_pid_ns = open("/proc/self/ns/pid", O_RDONLY | O_CLOEXEC);
    if (own_pid_ns < 0) return fail(why, size, "/proc/self/ns/pid");
    return 0;
}

pid_t ck_sandbox_fork(char *why, size_t size)
{
    if (own_pid_ns < 0) {
        errno = EINVAL;
        return fail(why, size, "the sandbox is not set up");
    }
    if (unshare(CLONE_NEWPID) != 0) return fail(why, size, "unshare (a PID namespace)");
    const pid_t pid = fork();
    const int saved = errno;
    /* the next children (addr2line, the next case) are the checker's again */
    if (pid != 0 && setns(own_pid_ns, CLONE_NEWPID) != 0 && pid > 0) {
        kill(pid, SIGKILL);
        waitpid(pid, NULL, 0);
        return fail(why, size, "setns (back to the checker's PID namespace)");
    }
    if (pid < 0) {
        errno = saved;
        return fail(why, size, "fork");
    }
    return pid;
}

/* No capability left, none to regain: the bounding set emptied, the
 * effective, permitted and inheritable sets cleared, no new privileges
 * through exec. */
static int drop_caps(void)
{
    for (int c = 0; c <= 63; ++c)
        if (prctl(PR_CAPBSET_DROP, c, 0, 0, 0) != 0 && errno != EINVAL) return -1;
    struct __user_cap_header_struct h = {_LINUX_CAPABILITY_VERSION_3, 0};
    struct __user_cap_data_struct d[2];
    memset(d, 0, sizeof d);
    if (syscall(SYS_capset, &h, d) != 0) return -1;
    return prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0);
}

int ck_sandbox_enter(const char *dir, char *why, size_t size)
{
    if (own_pid_ns >= 0) close(own_pid_ns);
    own_pid_ns = -1;
    if (unshare(CLONE_NEWNS | CLONE_NEWNET | CLONE_NEWIPC) != 0)
        return fail(why, size, "unshare (mount, network and IPC namespaces)");
    /* nothing mounted here reaches the host's mounts */
    if (mount(NULL, "/", NULL, MS_REC | MS_PRIVATE, NULL) != 0) return fail(why, size, "mount --make-rprivate /");
    if (chroot(dir) != 0 || chdir("/") != 0) return fail(why, size, "chroot");
    if (geteuid() == 0) {
        if (setgroups(0, NULL) != 0 || setgid(65534) != 0 || setuid(65534) != 0)
            return fail(why, size, "becoming the user nobody");
        if (prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0) return fail(why, size, "no new privileges");
    } else if (drop_caps() != 0) {
        return fail(why, size, "dropping the namespace's capabilities");
    }
    return 0;
}

int ck_sandbox_probe(char *why, size_t size)
{
    char dir[] = "/tmp/sidx-check-probe-XXXXXX";
    if (!mkdtemp(dir)) return fail(why, size, "mkdtemp");
    int pfd[2];
    if (pipe(pfd) != 0) {
        rmdir(dir);
        return fail(why, size, "pipe");
    }
    fflush(stdout);
    fflush(stderr);
    const pid_t pid = fork();
    if (pid == 0) { /* init, fork and enter, as the checker does them for a case */
        close(pfd[0]);
        char msg[256];
        int rc = ck_sandbox_init(msg, sizeof msg);
        if (rc == 0) {
            const pid_t c = ck_sandbox_fork(msg, sizeof msg);
            if (c == 0) _exit(ck_sandbox_enter(dir, msg, sizeof msg) == 0 ? 0 : (write(pfd[1], msg, strlen(msg)) < 0) + 1);
            int st = 0;
            rc = c > 0 && waitpid(c, &st, 0) == c && WIFEXITED(st) && WEXITSTATUS(st) == 0 ? 0 : -1;
            if (c < 0 && write(pfd[1], msg, strlen(msg)) < 0) {
            }
        } else if (write(pfd[1], msg, strlen(msg)) < 0) {
        }
        _exit(rc == 0 ? 0 : 1);
    }
    close(pfd[1]);
    int st = 0;
    if (pid < 0) {
        close(pfd[0]);
        rmdir(dir);
        return fail(why, size, "fork");
    }
    const ssize_t n = read(pfd[0], why, size ? size - 1 : 0);
    close(pfd[0]);
    while (waitpid(pid, &st, 0) < 0 && errno == EINTR) {
    }
    rmdir(dir);
    if (WIFEXITED(st) && WEXITSTATUS(st) == 0) return 0;
    if (size) {
        if (n <= 0) snprintf(why, size, "the test process stopped (status %d)", st);
        else why[n] = '\0';
    }
    return -1;
}
