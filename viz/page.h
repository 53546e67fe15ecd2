/* page.h — sidx-view --html: the viewer's 2D, build and 3D modes as one
 * self-contained web page (viz/html.c).  The page is viz/page.html, built
 * into the program (the Makefile turns it into a C array), with the
 * scene, the tree's build events and the ray's traversal events written
 * into it as one JSON object.  Not installed. */
#ifndef SIDX_VIZ_PAGE_H
#define SIDX_VIZ_PAGE_H

#include <stddef.h>
#include "view.h"

/* A page draws every triangle at every step: scenes above this are refused. */
#define VIEW_HTML_MAX_TRIANGLES 50000u
/* SAH candidate events kept for the build mode (the first nodes built get
 * their curve; later ones say the curve was left out). */
#define VIEW_HTML_MAX_CANDIDATES 20000u
/* A page larger than this is refused (a browser still opens it, but no
 * course page wants it). */
#define VIEW_HTML_MAX_BYTES (16u * 1024u * 1024u)

/* The template and its length (generated from viz/page.html at build time). */
extern const unsigned char sidx_page_html[];
extern const size_t sidx_page_html_len;

/* 0 when SCENE (file or built-in name) is small enough for a page; else -1
 * with msg saying the triangle count and the limit (or why it did not load). */
int view_html_check_scene(const char *scene, char *msg, size_t msg_size);

/* Writes v (its scene, build events and ray's traversal) as a page to path.
 * The page opens in mode `mode` at `step` (SIZE_MAX: the last step) and,
 * in 3D, with the boxes of tree level `level` (-1: none).  Returns 0, or -1
 * with msg filled (cannot write path, page too large). */
int view_write_html(const view_state *v, const char *path, view_mode mode, size_t step, int level, char *msg,
                    size_t msg_size);

#endif
