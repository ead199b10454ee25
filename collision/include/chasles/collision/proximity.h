#pragma once
/// \file
/// Placeholder (issue 4): per-link nearest-obstacle distances for potential fields.
