//! Loads a model saved by `gpodo fit --save` and predicts, as on-board
//! software would: the model file carries its input columns and the
//! experiment's z-scoring, so raw sensor values go in by column name.
//!
//! ```sh
//! cargo run --release -p gpodo-experiments -- fit experiments/paper.yaml --regressor "exact GP: rbf" --save gp.gpodo
//! cargo run --release -p gpodo-regressors --example load_model -- gp.gpodo
//! ```

use gpodo_regressors::model_file::ModelFile;
use gpodo_traits::SampleMatrix;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args()
        .nth(1)
        .ok_or("usage: load_model MODEL.gpodo")?;
    let file = ModelFile::load(path.as_ref())?;
    let predictor = file.predictor()?;
    // One row of raw inputs: here the training mean of every column.
    let row: Vec<f64> = match &file.input_standardizer {
        Some(s) => s.mean.clone(),
        None => vec![0.0; file.input_names.len()],
    };
    let rows = SampleMatrix::from_rows(row.len(), &[row])?;
    let p = predictor.predict(&file.input_names, &rows)?;
    println!("`{}` ({} inputs)", file.label, file.input_names.len());
    for (j, target) in file.target_names.iter().enumerate() {
        println!(
            "{target}: {:+.6} ± {:.6}",
            p.mean.get(0, j),
            p.variance.get(0, j).sqrt()
        );
    }
    Ok(())
}
