/* svg.c — hand-made SVG plots (no dependency): a labelled scatter plot and
 * a log-log line plot. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench.h"

static const char *const palette[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b",
                                      "#e377c2", "#7f7f7f", "#bcbd22", "#17becf", "#000000", "#393b79"};
#define PALETTE_N (sizeof palette / sizeof palette[0])

enum { W = 960, H = 640, ML = 80, MR = 230, MT = 50, MB = 70 };

typedef struct axis {
    double lo, hi;
    int log;
} axis;

static void xml_text(FILE *f, const char *s)
{
    for (; s && *s; ++s) {
        if (*s == '<') fputs("&lt;", f);
        else if (*s == '>') fputs("&gt;", f);
        else if (*s == '&') fputs("&amp;", f);
        else fputc(*s, f);
    }
}

static double tr(const axis *a, double v)
{
    if (a->log) v = log10(v);
    return (v - a->lo) / (a->hi - a->lo);
}

/* Range of the values (log10 when log; non-positive values clamp to floor). */
static axis make_axis(const double *v, size_t n, size_t stride, int logscale, double floor_)
{
    axis a = {INFINITY, -INFINITY, logscale};
    for (size_t i = 0; i < n; ++i) {
        double x = v[i * stride];
        if (logscale) x = log10(x > floor_ ? x : floor_);
        if (!isfinite(x)) continue;
        if (x < a.lo) a.lo = x;
        if (x > a.hi) a.hi = x;
    }
    if (!(a.lo <= a.hi)) { a.lo = 0; a.hi = 1; }
    if (logscale) {
        if (a.hi - a.lo >= 2.0) {
            a.lo = floor(a.lo);
            a.hi = ceil(a.hi);
        } else {
            a.lo -= 0.1;
            a.hi += 0.1;
            if (a.hi - a.lo < 0.5) { const double c = 0.5 * (a.lo + a.hi); a.lo = c - 0.25; a.hi = c + 0.25; }
        }
    } else {
        const double pad = (a.hi - a.lo) * 0.05 + (a.hi == a.lo ? 1.0 : 0.0);
        a.lo = a.lo >= 0 && a.lo - pad < 0 ? 0 : a.lo - pad;
        a.hi += pad;
    }
    return a;
}

static void frame(FILE *f, const char *title, const char *xlabel, const char *ylabel, const axis *ax, const axis *ay,
                  double xfloor)
{
    const int pw = W - ML - MR, ph = H - MT - MB;
    fprintf(f, "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" font-family=\"sans-serif\" "
               "font-size=\"12\">\n<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n", W, H);
    fprintf(f, "<text x=\"%d\" y=\"28\" font-size=\"17\" text-anchor=\"middle\">", ML + pw / 2);
    xml_text(f, title);
    fprintf(f, "</text>\n<rect x=\"%d\" y=\"%d\" width=\"%d\" height=\"%d\" fill=\"none\" stroke=\"#333\"/>\n", ML,
            MT, pw, ph);
    for (int which = 0; which < 2; ++which) {
        /* ticks: decades on log axes, 5 steps on linear ones */
        const axis *a = which ? ay : ax;
        /* ticks: linear axes 5 steps; log axes 1, 2, 5 x 10^k inside the range */
        double tv[64];
        int nt = 0;
        if (a->log) {
            for (int d = (int)floor(a->lo); d <= (int)ceil(a->hi) && nt < 60; ++d)
                for (int m = 0; m < 3; ++m) {
                    const double v = d + log10(m == 0 ? 1.0 : m == 1 ? 2.0 : 5.0);
                    if (v >= a->lo - 1e-9 && v <= a->hi + 1e-9 && (a->hi - a->lo < 3.0 || m == 0)) tv[nt++] = v;
                }
        } else {
            for (int k = 0; k <= 5; ++k) tv[nt++] = a->lo + k * (a->hi - a->lo) / 5;
        }
        for (int k = 0; k < nt; ++k) {
            const double frac = (tv[k] - a->lo) / (a->hi - a->lo);
            const double val = tv[k];
            char lab[32];
            if (a->log) {
                if (which == 0 && xfloor > 0 && fabs(val - log10(xfloor)) < 1e-9) snprintf(lab, sizeof lab, "0");
                else snprintf(lab, sizeof lab, "%g", pow(10.0, val));
            } else {
                snprintf(lab, sizeof lab, "%.3g", val);
            }
            if (which == 0) {
                const double x = ML + frac * pw;
                fprintf(f, "<line x1=\"%.1f\" y1=\"%d\" x2=\"%.1f\" y2=\"%d\" stroke=\"#ddd\"/>"
                           "<text x=\"%.1f\" y=\"%d\" text-anchor=\"middle\">%s</text>\n",
                        x, MT, x, MT + ph, x, MT + ph + 18, lab);
            } else {
                const double y = MT + ph - frac * ph;
                fprintf(f, "<line x1=\"%d\" y1=\"%.1f\" x2=\"%d\" y2=\"%.1f\" stroke=\"#ddd\"/>"
                           "<text x=\"%d\" y=\"%.1f\" text-anchor=\"end\">%s</text>\n",
                        ML, y, ML + pw, y, ML - 6, y + 4, lab);
            }
        }
    }
    fprintf(f, "<text x=\"%d\" y=\"%d\" text-anchor=\"middle\">", ML + pw / 2, H - 20);
    xml_text(f, xlabel);
    fprintf(f, "</text>\n<text x=\"18\" y=\"%d\" text-anchor=\"middle\" transform=\"rotate(-90 18 %d)\">",
            MT + ph / 2, MT + ph / 2);
    xml_text(f, ylabel);
    fprintf(f, "</text>\n");
}

static void legend(FILE *f, const char *const *names, int n)
{
    for (int s = 0; s < n; ++s) {
        const int y = MT + 10 + 18 * s;
        fprintf(f, "<circle cx=\"%d\" cy=\"%d\" r=\"5\" fill=\"%s\"/><text x=\"%d\" y=\"%d\">", W - MR + 20, y,
                palette[s % PALETTE_N], W - MR + 30, y + 4);
        xml_text(f, names[s]);
        fprintf(f, "</text>\n");
    }
}

int bench_svg_scatter(const char *path, const char *title, const char *xlabel, const char *ylabel, int xlog,
                      int ylog, const bench_point *pts, size_t n, const char *const *series_names, int nseries,
                      const char *const *shape_names, int nshapes)
{
    FILE *f = fopen(path, "w");
    if (!f) return 0;
    /* On a log x axis a value of 0 (no error at all) is drawn at the left edge, labelled "0". */
    double xfloor = INFINITY;
    for (size_t i = 0; i < n; ++i)
        if (pts[i].x > 0 && pts[i].x < xfloor) xfloor = pts[i].x;
    xfloor = isfinite(xfloor) ? pow(10.0, floor(log10(xfloor)) - 1.0) : 1e-7;
    const size_t m = n;
    double *xs = calloc(m + 1, sizeof *xs), *ys = calloc(m + 1, sizeof *ys);
    if (!xs || !ys) {
        free(xs);
        free(ys);
        fclose(f);
        return 0;
    }
    for (size_t i = 0; i < m; ++i) {
        xs[i] = xlog && !(pts[i].x > 0) ? xfloor : pts[i].x;
        ys[i] = pts[i].y;
    }
    axis ax = make_axis(xs, m, 1, xlog, xfloor);
    axis ay = make_axis(ys, m, 1, ylog, 1e-9);
    frame(f, title, xlabel, ylabel, &ax, &ay, xlog ? xfloor : 0);
    const int pw = W - ML - MR, ph = H - MT - MB;
    for (size_t i = 0; i < m; ++i) {
        const double x = ML + tr(&ax, xs[i]) * pw, y = MT + ph - tr(&ay, ys[i] > 0 || !ylog ? ys[i] : 1e-9) * ph;
        const char *col = palette[(size_t)pts[i].series % PALETTE_N];
        fprintf(f, "<g><title>");
        xml_text(f, pts[i].label);
        fprintf(f, " (error rate %g, %g Mrays/s)</title>", pts[i].x, pts[i].y);
        char style[96];
        if (pts[i].hollow) snprintf(style, sizeof style, "fill=\"white\" stroke=\"%s\" stroke-width=\"2\"", col);
        else snprintf(style, sizeof style, "fill=\"%s\" fill-opacity=\"0.85\"", col);
        if (pts[i].shape == 1)
            fprintf(f, "<rect x=\"%.1f\" y=\"%.1f\" width=\"9\" height=\"9\" %s/>", x - 4.5, y - 4.5, style);
        else if (pts[i].shape == 2)
            fprintf(f, "<polygon points=\"%.1f,%.1f %.1f,%.1f %.1f,%.1f\" %s/>", x, y - 6, x - 5.5, y + 4, x + 5.5,
                    y + 4, style);
        else
            fprintf(f, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"5\" %s/>", x, y, style);
        fprintf(f, "</g>\n");
        if (pts[i].show_label) {
            fprintf(f, "<text x=\"%.1f\" y=\"%.1f\" font-size=\"10\" fill=\"%s\">", x + 7, y - 4, col);
            xml_text(f, pts[i].label);
            fprintf(f, "</text>\n");
        }
    }
    for (int k = 0; k < nshapes; ++k) {
        /* shape legend below the colour legend */
        const int yy = MT + 10 + 18 * (nseries + 1 + k);
        const int xx = W - MR + 20;
        const int shape = k / 2, hollow = k % 2;
        char style[64];
        if (hollow) snprintf(style, sizeof style, "fill=\"white\" stroke=\"#333\" stroke-width=\"2\"");
        else snprintf(style, sizeof style, "fill=\"#333\"");
        if (shape == 1) fprintf(f, "<rect x=\"%d\" y=\"%d\" width=\"9\" height=\"9\" %s/>", xx - 4, yy - 4, style);
        else if (shape == 2)
            fprintf(f, "<polygon points=\"%d,%d %d,%d %d,%d\" %s/>", xx, yy - 6, xx - 5, yy + 4, xx + 5, yy + 4, style);
        else fprintf(f, "<circle cx=\"%d\" cy=\"%d\" r=\"5\" %s/>", xx, yy, style);
        fprintf(f, "<text x=\"%d\" y=\"%d\">", xx + 10, yy + 4);
        xml_text(f, shape_names[k]);
        fprintf(f, "</text>\n");
    }
    legend(f, series_names, nseries);
    fprintf(f, "</svg>\n");
    free(xs);
    free(ys);
    return fclose(f) == 0;
}

int bench_svg_lines(const char *path, const char *title, const char *xlabel, const char *ylabel,
                    const bench_point *pts, size_t n, const char *const *series_names, int nseries)
{
    FILE *f = fopen(path, "w");
    if (!f) return 0;
    const size_t m = n;
    double *xs = calloc(m + 1, sizeof *xs), *ys = calloc(m + 1, sizeof *ys);
    if (!xs || !ys) {
        free(xs);
        free(ys);
        fclose(f);
        return 0;
    }
    for (size_t i = 0; i < m; ++i) {
        xs[i] = pts[i].x;
        ys[i] = pts[i].y;
    }
    axis ax = make_axis(xs, m, 1, 1, 1e-9), ay = make_axis(ys, m, 1, 1, 1e-9);
    frame(f, title, xlabel, ylabel, &ax, &ay, 0);
    const int pw = W - ML - MR, ph = H - MT - MB;
    for (int s = 0; s < nseries; ++s) {
        fprintf(f, "<polyline fill=\"none\" stroke-width=\"2\" stroke=\"%s\" points=\"", palette[s % PALETTE_N]);
        for (size_t i = 0; i < m; ++i)
            if (pts[i].series == s && xs[i] > 0 && ys[i] > 0)
                fprintf(f, "%.1f,%.1f ", ML + tr(&ax, xs[i]) * pw, MT + ph - tr(&ay, ys[i]) * ph);
        fprintf(f, "\"/>\n");
        for (size_t i = 0; i < m; ++i)
            if (pts[i].series == s && xs[i] > 0 && ys[i] > 0)
                fprintf(f, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"3\" fill=\"%s\"/>\n", ML + tr(&ax, xs[i]) * pw,
                        MT + ph - tr(&ay, ys[i]) * ph, palette[s % PALETTE_N]);
    }
    legend(f, series_names, nseries);
    fprintf(f, "</svg>\n");
    free(xs);
    free(ys);
    return fclose(f) == 0;
}
