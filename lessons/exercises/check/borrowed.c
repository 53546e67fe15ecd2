/* borrowed.c — no borrowed answers (borrowed.h, symbols.def). */
#include "borrowed.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

static const ck_symbols table[] = {
#define SYMBOLS(n, may, writes) {n, may, writes},
#include "symbols.def"
#undef SYMBOLS
};

const ck_symbols *ck_symbols_of(const char *name)
{
    for (size_t k = 0; k < sizeof table / sizeof table[0]; ++k)
        if (!strcmp(table[k].name, name)) return &table[k];
    return NULL;
}

/* 1 if word is one of list's blank-separated words. */
static int in_list(const char *list, const char *word)
{
    const size_t n = strlen(word);
    for (const char *p = list; *p;) {
        p += strspn(p, " ");
        const size_t w = strcspn(p, " ");
        if (w == n && !strncmp(p, word, n)) return 1;
        p += w;
    }
    return 0;
}

/* Functions that find others by name or by walking the loaded program at
 * run time: through them a student's code reaches any function without
 * naming it. */
static const char *const lookups = "dlopen dlmopen dlsym dlvsym dladdr dladdr1 dlinfo dl_iterate_phdr";

/* The verdict on one symbol the object uses (defined = 0) or defines, or
 * NULL if it may; *rank orders the verdicts, the exercise's own answer
 * first. */
static const char *judge(const ck_symbols *s, const char *sym, int defined, char *buf, size_t size, int *rank)
{
    const int lib = !strncmp(sym, "sidx_", 5), kit = !strncmp(sym, "ex_", 3);
    *rank = defined ? 4 : lib && in_list(s->writes, sym) ? 0 : kit ? 1 : lib ? 3 : 2;
    if (defined) {
        if (!lib && !kit) return NULL;
        snprintf(buf, size, "defines %s, a name of the %s: it would replace the %s's own (name your functions "
                 "as the stub does)", sym, lib ? "library" : "checker", lib ? "library" : "checker");
        return buf;
    }
    if (lib && in_list(s->writes, sym))
        snprintf(buf, size, "uses %s, which this exercise asks you to write", sym);
    else if (lib && !in_list(s->may_call, sym))
        snprintf(buf, size, "uses %s, a function of the library this exercise does not let you call (it may call: "
                 "%s)", sym, s->may_call[0] ? s->may_call : "none of the library's, the headers' inline helpers only");
    else if (kit)
        snprintf(buf, size, "uses %s, a part of the checker (its reference, its cases): your code may not call it",
                 sym);
    else if (in_list(lookups, sym))
        snprintf(buf, size, "uses %s, which looks functions up at run time: the checker does not allow it", sym);
    else
        return NULL;
    return buf;
}

int ck_borrowed(const char *name, const char *obj, FILE *out, char *first, size_t size)
{
    if (size) first[0] = '\0';
    const ck_symbols *s = ck_symbols_of(name);
    static const ck_symbols none = {"", "", ""};
    if (!s) s = &none; /* an exercise without a line: the library closed, the C library open */
    int pfd[2];
    if (pipe(pfd) != 0) return -1;
    fflush(stdout);
    fflush(stderr);
    const pid_t pid = fork();
    if (pid < 0) {
        close(pfd[0]);
        close(pfd[1]);
        return -1;
    }
    if (pid == 0) {
        dup2(pfd[1], 1);
        close(pfd[0]);
        close(pfd[1]);
        const char *nm = getenv("NM");
        if (!nm || !nm[0]) nm = "nm";
        /* -P: "name type [value size]", one symbol a line; U and w (weak)
         * are undefined, an upper-case letter a global definition */
        execlp(nm, nm, "-P", obj, (char *)NULL);
        fprintf(stderr, "sidx-check: cannot run %s: %s\n", nm, strerror(errno));
        _exit(127);
    }
    close(pfd[1]);
    FILE *f = fdopen(pfd[0], "r");
    char line[1024], verdict[1024];
    /* the verdicts by rank, each rank's in nm's (alphabetical) order */
    char *by_rank[5] = {NULL};
    size_t rank_len[5] = {0};
    FILE *rank_out[5] = {NULL};
    for (int r = 0; r < 5; ++r) rank_out[r] = open_memstream(&by_rank[r], &rank_len[r]);
    int found = 0, lines = 0;
    while (f && fgets(line, sizeof line, f)) {
        ++lines;
        char sym[512], type[8];
        if (sscanf(line, "%511s %7s", sym, type) != 2) continue;
        const int undefined = !strcmp(type, "U") || !strcmp(type, "w") || !strcmp(type, "v");
        const int defined = !undefined && type[0] >= 'A' && type[0] <= 'Z';
        if (!undefined && !defined) continue;
        int rank;
        const char *v = judge(s, sym, defined, verdict, sizeof verdict, &rank);
        if (!v) continue;
        if (rank_out[rank]) fprintf(rank_out[rank], "%s\n", v);
        ++found;
    }
    if (f) fclose(f);
    else close(pfd[0]);
    for (int r = 0; r < 5; ++r) {
        if (!rank_out[r]) continue;
        fclose(rank_out[r]);
        if (by_rank[r][0] && size && !first[0]) snprintf(first, size, "%.*s", (int)strcspn(by_rank[r], "\n"), by_rank[r]);
        fputs(by_rank[r], out);
        free(by_rank[r]);
    }
    int st;
    while (waitpid(pid, &st, 0) < 0)
        if (errno != EINTR) return -1;
    /* every object defines or calls something: no line at all is no
     * reading of it (an NM that printed nothing) */
    if (!WIFEXITED(st) || WEXITSTATUS(st) != 0 || lines == 0) return -1;
    return found;
}
