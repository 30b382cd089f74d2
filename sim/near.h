/* Nearest words: what a user probably meant by a name no table has (a config
 * key, a command, an option), so a message can say "did you mean 'l2.size'?"
 * instead of listing every name. Distance is optimal string alignment: one
 * edit inserts, deletes or changes a character or swaps two neighbours
 * (l2.szie -> l2.size is one). */
#ifndef RTSIM_SIM_NEAR_H
#define RTSIM_SIM_NEAR_H

#include <stddef.h>

/* The edits between a and b (capped at 255: names are short). */
unsigned near_distance(const char *a, const char *b);

/* The names of list (separated by ", ") nearest to word, as "'a'", "'a' or
 * 'b'" or "'a', 'b' or 'c'" (at most 3, in list order) into buf; their
 * number, 0 (buf "") when none is near. A name is near when it is within
 * max(1, strlen(word) / 3) edits, or when word is its part after the last
 * '.' (size -> l1.size, l2.size); only the nearest distance is named. */
unsigned near_words(const char *word, const char *list, char *buf, size_t cap);

#endif
