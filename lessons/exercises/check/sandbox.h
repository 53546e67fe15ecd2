/* sandbox.h — where a student's code runs: Linux namespaces, for root and
 * for any user (docs/exercises.md, "What the limits do").
 *
 * The checker first calls ck_sandbox_init: run as an ordinary user it
 * moves into a user namespace of its own, mapping only its own uid, where
 * it holds the capabilities to make the other namespaces (root needs
 * none).  Each case's process is then made with ck_sandbox_fork: it is
 * the first process (init) of a new PID namespace, so its kill(-1)
 * reaches only its own processes.  There it calls ck_sandbox_enter: new
 * mount, network and IPC namespaces, the case's directory as its root
 * (chroot: nothing else of the file system is there to read or write),
 * and no privilege left (root becomes the user nobody, a user drops the
 * namespace's capabilities).  The network namespace has only a loopback
 * device, and that is down: no connection reaches anything. */
#ifndef SIDX_CK_SANDBOX_H
#define SIDX_CK_SANDBOX_H

#include <stddef.h>
#include <sys/types.h>

/* 0, or -1 with the step that failed and why in why (size bytes). */
int ck_sandbox_init(char *why, size_t size);

/* fork(2) into a new PID namespace (after ck_sandbox_init): the child's
 * pid in the parent, 0 in the child, -1 with why. */
pid_t ck_sandbox_fork(char *why, size_t size);

/* In the child of ck_sandbox_fork: 0, or -1 with why (the process is
 * left half-contained: it should exit). */
int ck_sandbox_enter(const char *dir, char *why, size_t size);

/* In a child, whether all three work here: 0, or -1 with why. */
int ck_sandbox_probe(char *why, size_t size);

#endif
