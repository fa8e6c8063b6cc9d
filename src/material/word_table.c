/*
 * The table of words (material/word_table.h). Adding a word: its file
 * src/material/word_NAME.c with its descriptor, and one entry here.
 */
#include "material/word_table.h"

const ll_word_desc *const ll_word_table[] = {
    &ll_word_diffuse, &ll_word_dielectric, &ll_word_conductor, &ll_word_medium,
    &ll_word_measured,
};

const size_t ll_word_table_size = sizeof ll_word_table / sizeof ll_word_table[0];
