/* c-consumer: plain C99 against shadowtiles.h (pkg-config shadowtiles).
 *
 *   c-consumer LOCATION POINTS_FILE METHOD
 *
 * LOCATION is a store directory or a server URL; POINTS_FILE holds one "x y z" world point per line.
 * Prints one line per point, "lit value" (lit 1/0, the stored value compared with, %.9g), answered
 * through one batch call. Exit status 1 with the library's message on any error. */
#include <stdio.h>
#include <stdlib.h>

#include <shadowtiles.h>

static int fail(const char* what) {
  fprintf(stderr, "c-consumer: %s: %s\n", what, shadowtiles_last_error());
  return 1;
}

/* Reads "x y z" lines into a growing array; returns the count, or (size_t)-1 on a parse error. */
static size_t read_points(FILE* in, double** points) {
  size_t count = 0, capacity = 1024;
  double* data = malloc(3 * capacity * sizeof(double));
  double x, y, z;
  int fields;
  if (!data) return (size_t)-1;
  while ((fields = fscanf(in, "%lf %lf %lf", &x, &y, &z)) == 3) {
    if (count == capacity) {
      double* grown = realloc(data, 3 * 2 * capacity * sizeof(double));
      if (!grown) { free(data); return (size_t)-1; }
      data = grown;
      capacity *= 2;
    }
    data[3 * count] = x;
    data[3 * count + 1] = y;
    data[3 * count + 2] = z;
    ++count;
  }
  if (fields != EOF) { free(data); return (size_t)-1; }
  *points = data;
  return count;
}

int main(int argc, char** argv) {
  shadowtiles_map* map = NULL;
  shadowtiles_info info;
  double* points = NULL;
  uint8_t* lit;
  float* values;
  size_t count, i;
  FILE* in;
  int status = 0;

  if (argc != 4) {
    fprintf(stderr, "usage: c-consumer LOCATION POINTS_FILE METHOD\n");
    return 2;
  }
  if (shadowtiles_open(argv[1], 0, &map) != SHADOWTILES_OK) return fail("open");
  if (shadowtiles_get_info(map, &info) != SHADOWTILES_OK) return fail("info");
  fprintf(stderr, "c-consumer: libshadowtiles %s (ABI %d), %u^2 texels in tiles of %u^2\n", shadowtiles_version(),
          shadowtiles_abi_version(), (unsigned)info.resolution, (unsigned)info.tile_size);

  in = fopen(argv[2], "r");
  if (!in) { perror(argv[2]); shadowtiles_close(map); return 1; }
  count = read_points(in, &points);
  fclose(in);
  if (count == (size_t)-1) { fprintf(stderr, "c-consumer: %s: malformed points\n", argv[2]); shadowtiles_close(map); return 1; }

  lit = malloc(count ? count : 1);
  values = malloc((count ? count : 1) * sizeof(float));
  if (!lit || !values) { fprintf(stderr, "c-consumer: out of memory\n"); status = 1; goto done; }
  if (shadowtiles_query_batch(map, argv[3], points, count, -1.0, 0, lit, values, NULL) != SHADOWTILES_OK) {
    status = fail("query_batch");
    goto done;
  }
  for (i = 0; i < count; ++i) printf("%d %.9g\n", lit[i], (double)values[i]);

done:
  free(lit);
  free(values);
  free(points);
  shadowtiles_close(map);
  return status;
}
