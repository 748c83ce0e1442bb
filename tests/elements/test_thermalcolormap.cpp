#include "element_support.h"
