/*
 * Bake a scene and render it from the cache through wpbgi's C ABI.
 *
 *   bake_and_render SCENE CACHE OUT.pfm [POINTS [BOUNCES [SIZE]]]
 *
 * POINTS: surfels (default: the draft preset's); BOUNCES: indirect bounces (-1, the default:
 * automatic); SIZE: the image's side in pixels (default 128). The image is written as a
 * Portable Float Map (linear RGB, 32-bit floats), OUT.pfm, and as OUT.exr next to it.
 *
 * Build, from the repository root, after `cargo build --release -p wpbgi-plugin`:
 *
 *   cc -std=c99 -Wall -Wextra -I plugin/include plugin/examples/bake_and_render.c \
 *      -L target/release -lwpbgi_plugin -Wl,-rpath,"$PWD/target/release" -o bake_and_render
 */
#include "wpbgi.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Prints the stage and how far it is; returning non-zero would cancel the bake. */
static int32_t on_progress(const char *stage, float fraction, void *user_data) {
    int *reports = (int *)user_data;
    ++*reports;
    fprintf(stderr, "\r  %-14s %3.0f%%", stage, 100.0f * fraction);
    return 0;
}

static int failed(const char *what) {
    fprintf(stderr, "\n%s failed: %s\n", what, wpbgi_last_error());
    return 1;
}

/* A Portable Float Map: little-endian ("-1.0"), rows bottom to top. */
static int write_pfm(const char *path, const float *rgb, uint32_t width, uint32_t height) {
    FILE *f = fopen(path, "wb");
    if (!f) {
        perror(path);
        return 1;
    }
    fprintf(f, "PF\n%u %u\n-1.0\n", width, height);
    for (uint32_t row = height; row-- > 0;) {
        fwrite(rgb + (size_t)row * width * 3, sizeof(float), (size_t)width * 3, f);
    }
    return fclose(f) == 0 ? 0 : 1;
}

int main(int argc, char **argv) {
    if (argc < 4) {
        fprintf(stderr, "usage: %s SCENE CACHE OUT.pfm [POINTS [BOUNCES [SIZE]]]\n", argv[0]);
        return 2;
    }
    if (wpbgi_abi_version() != WPBGI_ABI_VERSION) {
        fprintf(stderr, "this program was built for wpbgi ABI %d but the library is ABI %u\n",
                WPBGI_ABI_VERSION, wpbgi_abi_version());
        return 1;
    }

    WpbgiScene *scene = NULL;
    if (wpbgi_scene_load(argv[1], &scene) != WPBGI_OK) return failed("loading the scene");

    WpbgiBakeSettings bake;
    wpbgi_bake_settings_init(&bake);
    if (argc > 4) bake.points = strtoull(argv[4], NULL, 10);
    if (argc > 5) bake.bounces = (int32_t)strtol(argv[5], NULL, 10);
    int reports = 0;
    fprintf(stderr, "baking %s (wpbgi %s)\n", argv[1], wpbgi_version());
    if (wpbgi_bake(scene, &bake, argv[2], on_progress, &reports) != WPBGI_OK) {
        wpbgi_scene_free(scene);
        return failed("the bake");
    }
    fprintf(stderr, "\n  %d progress reports; wrote %s\n", reports, argv[2]);

    WpbgiCache *cache = NULL;
    if (wpbgi_cache_open(scene, argv[2], &cache) != WPBGI_OK) {
        wpbgi_scene_free(scene);
        return failed("opening the cache");
    }
    char hash[33];
    wpbgi_cache_hash(cache, hash, sizeof hash);
    fprintf(stderr, "  cache hash %s\n", hash);

    WpbgiRenderSettings render;
    wpbgi_render_settings_init(&render);
    render.width = render.height = argc > 6 ? (uint32_t)strtoul(argv[6], NULL, 10) : 128;
    size_t floats = (size_t)render.width * render.height * 3;
    float *rgb = malloc(floats * sizeof(float));
    int status = 1;
    if (!rgb) {
        fprintf(stderr, "out of memory\n");
    } else if (wpbgi_render(scene, cache, &render, rgb, floats) != WPBGI_OK) {
        failed("the render");
    } else if (write_pfm(argv[3], rgb, render.width, render.height) == 0) {
        /* The same render again, written by the library. */
        char exr[4096];
        size_t n = strlen(argv[3]);
        snprintf(exr, sizeof exr, "%.*s.exr", (int)(n > 4 ? n - 4 : n), argv[3]);
        if (wpbgi_render_to_file(scene, cache, &render, exr) != WPBGI_OK) {
            failed("writing the EXR");
        } else {
            fprintf(stderr, "  wrote %s and %s (%ux%u)\n", argv[3], exr, render.width, render.height);
            status = 0;
        }
    }
    free(rgb);
    wpbgi_cache_free(cache);
    wpbgi_scene_free(scene);
    return status;
}
